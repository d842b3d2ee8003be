"""`roughness studio`: the browser studio (the `studio` extra), served on this machine."""
from __future__ import annotations

import argparse
import sys

from .common import count

DEFAULT_PORT = 8080


def add_parser(sub) -> None:
    st = sub.add_parser("studio", help="the Roughness Studio: design textures by feel in the browser (the 'studio' "
                                       "extra)")
    st.add_argument("--host", default="127.0.0.1",
                    help="address to serve on (default: 127.0.0.1, this machine only); any other address prints a "
                         "warning and requires the access token printed at start on every request")
    st.add_argument("--port", type=count(65535), default=DEFAULT_PORT, help=f"port (default: {DEFAULT_PORT})")
    st.add_argument("--no-browser", action="store_true", help="do not open a browser (default: open one)")
    st.set_defaults(run=run, flags={"host": "--host", "port": "--port"})


def run(args: argparse.Namespace) -> int:
    import secrets

    from roughness.studio.app import LOCAL_HOSTS, StudioSettings, serve

    token = None
    if args.host not in LOCAL_HOSTS:
        token = secrets.token_urlsafe(24)
        print(f"roughness studio: warning: serving on {args.host}, reachable from other machines; every request "
              f"needs the access token. Open: http://{args.host}:{args.port}/?token={token}", file=sys.stderr,
              flush=True)
    serve(StudioSettings(args.host, args.port, not args.no_browser, token))
    return 0
