"""Open an interactive transition studio in the browser (viser; works over SSH forwarding).

The subject's humanoid plays clip 1 -> window -> clip 2 in a loop. Change the clips, their
frames, the method, alpha or the window length and the transition is recomputed at once;
the bodies that fail a kinematic check on the current frame (a joint beyond its limit,
self-collision, below the floor) are tinted red and such frames are marked red on the
strip; a second method can be ghosted beside it.

Only the studio's own page may drive it: a websocket from any other web page (any other
Origin) is refused with HTTP 403, unless allowed with --allow-origin. Exports go into the
--out folder only, and never overwrite a file. It serves 127.0.0.1 by default; to use it
from another machine, forward the port over SSH (ssh -L 8080:127.0.0.1:8080 HOST) rather
than serving a non-loopback --host, which anyone who can reach the port could drive.

Example:
  upm studio --from 02_01 --to 02_03 --port 8080     # then open http://localhost:8080
"""

from __future__ import annotations

HELP = "interactive transition studio in the browser (needs viser)"


def configure(parser) -> None:
    from upm.commands.common import add_data_argument

    add_data_argument(parser)
    parser.add_argument("--from", dest="clip1", default="02_01", metavar="CLIP",
                        help="clip 1 (default 02_01)")
    parser.add_argument("--to", dest="clip2", default="02_03", metavar="CLIP",
                        help="clip 2 (default 02_03)")
    parser.add_argument("--map", metavar="MAP.npz", default=None,
                        help="trained posture map (upm train), for --method upm/som")
    parser.add_argument("--config", metavar="FILE.toml", default=None,
                        help="the humanoid's configuration for the method performed (its "
                        "[offline] section sets the search), from a TOML file (default: "
                        "the built-in constants)")
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on "
                        "(default 127.0.0.1; use SSH port forwarding to reach it)")
    parser.add_argument("--port", type=int, default=8080, help="port (default 8080)")
    parser.add_argument("--out", metavar="DIR", default="studio-exports",
                        help="folder the page's exports are written to, and nowhere else "
                        "(default ./studio-exports, created on the first export)")
    parser.add_argument("--allow-origin", action="append", default=[], metavar="ORIGIN",
                        help="also let in websockets from the web page at ORIGIN "
                        "(scheme://host:port; repeatable); the studio's own page "
                        "(localhost, 127.0.0.1, [::1] at its port) is always let in")


def run(args) -> int:
    import sys
    from pathlib import Path

    from controller.offline.performer import install
    from upm.commands.common import controller_config
    from upm.core.errors import UsageError
    from upm.motion.catalog import Catalog

    try:
        import viser  # noqa: F401
    except ImportError:
        raise UsageError("upm studio needs viser: pip install 'upm-controller[studio]'") from None
    from studio.app import Studio
    from studio.origin import is_loopback, parse_allowed
    from studio.session import Session

    allowed = parse_allowed(args.allow_origin)
    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port {args.port}: give a port from 0 to 65535")
    if Path(args.out).exists() and not Path(args.out).is_dir():
        raise UsageError(f"--out {args.out}: not a folder")
    if not is_loopback(args.host):
        print(f"upm studio: warning: serving {args.host}, not loopback: anyone who can reach "
              f"port {args.port} can drive the studio (and write exports); prefer SSH port "
              f"forwarding: ssh -L {args.port}:127.0.0.1:{args.port} HOST", file=sys.stderr,
              flush=True)
    performer_config = controller_config(args)
    install()  # the method performed, as the other commands install it
    catalog = Catalog(args.data)
    for name in (args.clip1, args.clip2):
        if name not in catalog:
            raise UsageError(f"no clip {name} in {args.data or 'the catalogue'}")
    session = Session(catalog, args.clip1, args.clip2, args.map,
                      performer_config=performer_config)
    studio = Studio(session, args.host, args.port, out=args.out, allow_origins=allowed)
    print(f"upm studio: open http://{args.host}:{studio.port} (Ctrl-C stops); exports go "
          f"to {studio.exports.root}", flush=True)
    try:
        studio.play_forever()
    except KeyboardInterrupt:
        studio.stop()
    return 0
