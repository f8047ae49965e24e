#!/usr/bin/env python3
"""Static file server for the Superpixel Soup page (Python standard library only).

Serves a folder (default: the repository root) with the right Content-Type for wasm and ES
modules, the cross-origin isolation headers that wasm threads (SharedArrayBuffer) need, and no
caching, so a rebuilt module is always picked up.

    python3 scripts/serve.py [--port PORT] [--bind ADDRESS] [--dir FOLDER]

Port 0 picks a free port. The first line printed starts `serving http://HOST:PORT/`
(tests read the port from it). Defaults: port from env PORT or 8080, address 127.0.0.1.
"""

import argparse
import functools
import http.server
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Handler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".wasm": "application/wasm",
        ".js": "text/javascript",
        ".mjs": "text/javascript",
        ".json": "application/json",
        ".css": "text/css",
        ".html": "text/html; charset=utf-8",
        ".svg": "image/svg+xml",
    }

    def end_headers(self):
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        self.send_header("Cache-Control", "no-cache")
        super().end_headers()

    def log_message(self, format, *args):
        # One short line per request on stderr; quiet when SERVE_QUIET is set (tests).
        if not os.environ.get("SERVE_QUIET"):
            super().log_message(format, *args)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=int(os.environ.get("PORT", "8080")))
    parser.add_argument("--bind", default="127.0.0.1")
    parser.add_argument("--dir", default=ROOT)
    args = parser.parse_args()

    handler = functools.partial(Handler, directory=args.dir)
    try:
        server = http.server.ThreadingHTTPServer((args.bind, args.port), handler)
    except OSError as e:
        sys.exit(f"serve.py: cannot listen on {args.bind}:{args.port}: {e.strerror}")
    host, port = server.server_address[:2]
    shown = "localhost" if host == "127.0.0.1" else host
    print(f"serving http://{shown}:{port}/ (from {args.dir}; Ctrl-C stops)", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


if __name__ == "__main__":
    main()
