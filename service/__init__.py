"""sphereplan's transports: the CLI, the HTTP app and the Zenoh node, thin adapters over one service."""
