"""The studio's websocket lets in only its own page: an Origin check on viser's handshake.

Browsers do not apply the same-origin policy to websockets: any page the user visits
could open ``ws://127.0.0.1:8080``, read the session and send GUI events (cross-site
WebSocket hijacking). Every browser sends an ``Origin`` header on a websocket handshake,
so the studio refuses one whose Origin is not its own page: ``http://`` the host and port
it serves, in its ``localhost`` / ``127.0.0.1`` / ``[::1]`` spellings, or an origin the user
allowed (``upm studio --allow-origin``). A refused handshake is answered HTTP 403 and
logged (logger ``studio.origin``); it gets no GUI message, since viser's handler never
runs. A handshake with no Origin at all (not a browser) is refused too. The page's own
files (plain HTTP requests) are served as before: they are viser's public client.

viser (pinned in pyproject.toml) has no handshake hook of its own: it passes its own
``process_request`` to ``websockets.asyncio.server.serve`` from its server thread. While a
studio's :class:`viser.ViserServer` starts, :func:`guarded_viser` wraps that ``serve`` so
that viser's ``process_request`` runs after the Origin check, then puts ``serve`` back; it
fails loudly if viser did not call it (a viser that starts its server another way must
not run unguarded).
"""

from __future__ import annotations

import contextlib
import http
import ipaddress
import logging
import threading
from urllib.parse import urlsplit

from upm.core.errors import UsageError

LOG = logging.getLogger("studio.origin")
#: The loopback spellings of the studio's own host.
LOOPBACK_HOSTS = ("localhost", "127.0.0.1", "[::1]")
_SERVE_LOCK = threading.Lock()


def normalise_origin(text: str) -> str:
    """``scheme://host[:port]`` in lower case with the port always written.

    Raises
    ------
    ValueError
        Not an origin (no http/https scheme or host, or a path, query or user part).
    """
    parts = urlsplit(text.strip())
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise ValueError(f"origin {text!r}: write scheme://host[:port], e.g. http://myhost:8080")
    if parts.path not in ("", "/") or parts.query or parts.fragment or parts.username:
        raise ValueError(f"origin {text!r}: an origin has no path, query or user part")
    try:
        port = parts.port or (443 if parts.scheme == "https" else 80)
    except ValueError:
        raise ValueError(f"origin {text!r}: bad port") from None
    host = parts.hostname.lower()
    if ":" in host:
        host = f"[{host}]"
    return f"{parts.scheme}://{host}:{port}"


def parse_allowed(origins) -> tuple[str, ...]:
    """``--allow-origin`` values, normalised; a bad one is a one-line usage error."""
    try:
        return tuple(normalise_origin(o) for o in origins or ())
    except ValueError as error:
        raise UsageError(f"--allow-origin: {error}") from None


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an address) serves this machine alone."""
    if host.strip("[]").lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def own_origins(host: str, port: int, allowed=()) -> frozenset[str]:
    """The origins of the studio's own page at ``host:port``: its loopback spellings, the
    host it was given (unless a wildcard such as ``0.0.0.0``), and ``allowed``."""
    hosts = set(LOOPBACK_HOSTS)
    bare = host.strip("[]")
    if bare and bare not in ("0.0.0.0", "::"):
        hosts.add(f"[{bare}]" if ":" in bare else bare)
    return frozenset({normalise_origin(f"http://{h}:{port}") for h in hosts} | set(allowed))


class OriginGuard:
    """The handshake check of one studio: ``host`` as served, and the ``allowed`` origins
    (normalised). ``refused`` counts the handshakes turned away."""

    def __init__(self, host: str, allowed=()):
        self.host = host
        self.allowed = tuple(allowed)
        self.refused = 0
        self.installed = False

    def check(self, connection, request):
        """``process_request`` for websockets: None (go on) or a 403 response."""
        if request.headers.get("Upgrade", "").lower() != "websocket":
            return None  # the page's files
        port = connection.local_address[1]
        origin = request.headers.get("Origin")
        try:
            ok = origin is not None and normalise_origin(origin) in own_origins(
                self.host, port, self.allowed)
        except ValueError:
            ok = False
        if ok:
            return None
        self.refused += 1
        LOG.warning("upm studio: refused a websocket from origin %r (not this studio's page "
                    "on port %d; allow it with --allow-origin)", origin, port)
        return connection.respond(http.HTTPStatus.FORBIDDEN,
                                  "Forbidden: this page's origin may not drive the studio.\n")

    def wrap(self, serve):
        """``serve`` with :meth:`check` before the ``process_request`` it is given."""
        guard = self

        def guarded_serve(handler, *args, process_request=None, **kwargs):
            guard.installed = True

            def process(connection, request):
                refused = guard.check(connection, request)
                if refused is not None or process_request is None:
                    return refused
                return process_request(connection, request)

            return serve(handler, *args, process_request=process, **kwargs)

        return guarded_serve


@contextlib.contextmanager
def guarded_viser(guard: OriginGuard):
    """While the body starts a :class:`viser.ViserServer`, its websocket server gets
    ``guard``'s Origin check (``guard.installed`` tells whether viser's server took it: the
    caller stops a server that did not). One studio starts at a time in a process."""
    import websockets.asyncio.server as ws_server

    with _SERVE_LOCK:
        original = ws_server.serve
        ws_server.serve = guard.wrap(original)
        try:
            yield guard
        finally:
            ws_server.serve = original
