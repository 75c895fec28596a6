"""Open an interactive transition studio in the browser (viser; works over SSH forwarding).

The subject's humanoid plays clip 1 -> window -> clip 2 in a loop. Change the clips, their
frames, the method, alpha or the window length and the transition is recomputed at once;
the bodies that fail a kinematic check on the current frame (a joint beyond its limit,
self-collision, below the floor) are tinted red and such frames are marked red on the
strip; a second method can be ghosted beside it.

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
    parser.add_argument("--host", default="127.0.0.1", help="address to serve on "
                        "(default 127.0.0.1; use SSH port forwarding to reach it)")
    parser.add_argument("--port", type=int, default=8080, help="port (default 8080)")


def run(args) -> int:
    from upm.core.errors import UsageError
    from upm.motion.catalog import Catalog

    try:
        import viser  # noqa: F401
    except ImportError:
        raise UsageError("upm studio needs viser: pip install 'upm-controller[studio]'") from None
    from studio.app import Studio
    from studio.session import Session

    catalog = Catalog(args.data)
    for name in (args.clip1, args.clip2):
        if name not in catalog:
            raise UsageError(f"no clip {name} in {args.data or 'the catalogue'}")
    studio = Studio(Session(catalog, args.clip1, args.clip2, args.map), args.host, args.port)
    print(f"upm studio: open http://{args.host}:{studio.port} (Ctrl-C stops)", flush=True)
    try:
        studio.play_forever()
    except KeyboardInterrupt:
        studio.stop()
    return 0
