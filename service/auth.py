"""One security model for every door: who may ask the service to work, and where it may listen.

The service has one secret, the bearer token (``serve --token-file``). HTTP requests carry it in
``Authorization: Bearer <token>``; Zenoh queries and the robots' ``pose``/``goal`` puts carry the same bytes
``Bearer <token>`` as the message's **attachment** (Zenoh's per-message metadata), so a peer that can reach the
node but has no token gets nothing planned: a query is answered ``reply_err`` with the 401 JSON naming
``attachment``, a sample is dropped (and logged). Zenoh's own user/password authentication and access-control
list (``deploy/zenoh/service.json5``) are the other way to lock the Zenoh door; either one counts as
credentials. A door listening beyond loopback needs credentials or the operator's explicit ``--insecure``:
:func:`exposure_problem` says what is wrong, for HTTP (``--host``) and Zenoh (``--zenoh-listen`` or the
listen endpoints of a ``--zenoh-config``) alike.
"""

from __future__ import annotations

import hmac
import ipaddress
from collections.abc import Iterable
from typing import Any

#: the header / attachment scheme
SCHEME = b"Bearer "


def credential(token: str) -> bytes:
    """What a client sends: ``Bearer <token>`` (the HTTP header value and the Zenoh attachment alike)."""
    return SCHEME + token.encode()


def token_ok(given: bytes | None, token: str | None) -> bool:
    """True when no token is configured, or ``given`` is exactly ``Bearer <token>`` (constant-time compare)."""
    if token is None:
        return True
    return given is not None and hmac.compare_digest(given, credential(token))


def loopback_host(host: str) -> bool:
    """``host`` (an IP address or ``localhost``) is a loopback address; a host name may resolve anywhere."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def loopback_endpoint(endpoint: str) -> bool:
    """A Zenoh locator (``tcp/127.0.0.1:7447``, ``tls/[::1]:7447#...``, ``unixsock-stream/path``) reachable only
    from this machine."""
    proto, _, address = endpoint.partition("/")
    if proto.startswith("unixsock") or proto == "unixpipe":
        return True
    address = address.split("#", 1)[0].split("?", 1)[0]
    host = address.rsplit(":", 1)[0] if ":" in address else address
    return loopback_host(host)


def zenoh_listen_endpoints(config: Any) -> list[str] | None:
    """The endpoints a ``zenoh.Config`` listens on; None when it does not say (a peer or router then listens on
    every interface)."""
    import json

    mode = json.loads(config.get_json("mode") or "null") or "peer"
    if mode == "client":
        return []
    endpoints = json.loads(config.get_json("listen/endpoints") or "null")
    if isinstance(endpoints, dict):  # per-mode form: {router: [...], peer: [...]}
        endpoints = endpoints.get(mode)
    if endpoints is None:
        return None
    return [str(e) for e in endpoints]


def zenoh_has_credentials(config: Any) -> bool:
    """The config authenticates every session with user/password (``transport/auth/usrpwd``)."""
    import json

    user = json.loads(config.get_json("transport/auth/usrpwd/user") or "null")
    dictionary = json.loads(config.get_json("transport/auth/usrpwd/dictionary_file") or "null")
    return bool(user) and bool(dictionary)


def exposure_problem(endpoints: Iterable[str] | None, credentials: bool, insecure: bool) -> str | None:
    """Why listening on ``endpoints`` is refused (None: allowed): a non-loopback endpoint, or an unspecified
    one (every interface), needs ``credentials`` or ``insecure``."""
    if credentials or insecure:
        return None
    if endpoints is None:
        return "listens on every interface (no listen endpoints given)"
    exposed = [e for e in endpoints if not loopback_endpoint(e)]
    if exposed:
        return f"listens beyond loopback on {', '.join(exposed)}"
    return None
