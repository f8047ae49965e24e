#!/usr/bin/env python3
"""Static file server for the Superpixel Soup page (Python standard library only).

Serves a folder (default: the repository root) with the right Content-Type for wasm and ES
modules, the cross-origin isolation headers that wasm threads (SharedArrayBuffer) need, gzip
for text and wasm when the browser accepts it (as web hosts do; the wasm modules shrink to about
a third), and no caching without revalidation, so a rebuilt module is always picked up.

    python3 scripts/serve.py [--port PORT] [--bind ADDRESS] [--dir FOLDER]

Port 0 picks a free port. The first line printed starts `serving http://HOST:PORT/`
(tests read the port from it). Defaults: port from env PORT or 8080, address 127.0.0.1.
"""

import argparse
import email.utils
import functools
import gzip
import http.server
import io
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

    # Sent gzip-compressed when the request accepts it.
    compressible = {".wasm", ".js", ".mjs", ".css", ".html", ".json", ".svg", ".txt"}
    # (path, modification time, size) -> compressed bytes, shared by all requests.
    gzip_cache = {}

    def send_head(self):
        path = self.translate_path(self.path)
        if os.path.isdir(path) and self.path.split("?")[0].endswith("/"):
            path = os.path.join(path, "index.html")
        accepts_gzip = "gzip" in self.headers.get("Accept-Encoding", "")
        if not (accepts_gzip and os.path.isfile(path)
                and os.path.splitext(path)[1] in self.compressible):
            return super().send_head()
        stat = os.stat(path)
        since = self.headers.get("If-Modified-Since")
        if since is not None:
            try:
                if int(stat.st_mtime) <= email.utils.parsedate_to_datetime(since).timestamp():
                    self.send_response(http.server.HTTPStatus.NOT_MODIFIED)
                    self.end_headers()
                    return None
            except (TypeError, ValueError, OverflowError):
                pass  # ill-formed date: send the file
        key = (path, stat.st_mtime_ns, stat.st_size)
        body = self.gzip_cache.get(key)
        if body is None:
            with open(path, "rb") as f:
                body = gzip.compress(f.read(), compresslevel=6)
            self.gzip_cache[key] = body
        self.send_response(http.server.HTTPStatus.OK)
        self.send_header("Content-Type", self.guess_type(path))
        self.send_header("Content-Encoding", "gzip")
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Vary", "Accept-Encoding")
        self.send_header("Last-Modified", self.date_time_string(stat.st_mtime))
        self.end_headers()
        return io.BytesIO(body)

    def end_headers(self):
        self.send_header("Cross-Origin-Opener-Policy", "same-origin")
        self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        self.send_header("Cache-Control", "no-cache")
        super().end_headers()

    def log_message(self, format, *args):
        # One short line per request on stderr; quiet when SERVE_QUIET is set (tests).
        if not os.environ.get("SERVE_QUIET"):
            super().log_message(format, *args)


class Server(http.server.ThreadingHTTPServer):
    def handle_error(self, request, client_address):
        # A browser that closes a connection mid-transfer (a tab closed, a worker restarted by a
        # cancel) is normal, not an error worth a traceback.
        if isinstance(sys.exc_info()[1], (BrokenPipeError, ConnectionResetError)):
            return
        super().handle_error(request, client_address)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=int(os.environ.get("PORT", "8080")))
    parser.add_argument("--bind", default="127.0.0.1")
    parser.add_argument("--dir", default=ROOT)
    args = parser.parse_args()

    handler = functools.partial(Handler, directory=args.dir)
    try:
        server = Server((args.bind, args.port), handler)
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
