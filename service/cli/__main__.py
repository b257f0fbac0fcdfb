"""``python -m service.cli``: the ``sphereplan`` command line, for a checkout that is not installed."""

from service.cli import main

raise SystemExit(main())
