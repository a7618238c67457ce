#!/usr/bin/env python3
"""serve.py - the static file server `crowdbake view` runs: Python's http.server on a socket the
command has already bound to 127.0.0.1 (so it knows and prints the port before this starts).

  python3 web/serve.py --fd N --directory SITE

Serves SITE (links followed) until Ctrl-C, then exits 0. Requests are not logged; errors are."""
import argparse
import functools
import http.server
import socket
import sys


class Handler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map,
                      '.mjs': 'text/javascript', '.js': 'text/javascript', '.glsl': 'text/plain',
                      '.json': 'application/json', '.pal': 'application/octet-stream',
                      '.exr': 'application/octet-stream', '.glb': 'model/gltf-binary'}

    def end_headers(self):
        self.send_header('Cache-Control', 'no-cache')  # a re-bake shows on reload
        super().end_headers()

    def log_message(self, fmt, *args):
        pass

    def log_error(self, fmt, *args):
        if not fmt.startswith('code 404'):
            sys.stderr.write('crowdbake view: %s\n' % (fmt % args))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--fd', type=int, required=True)
    ap.add_argument('--directory', required=True)
    a = ap.parse_args()
    server = http.server.ThreadingHTTPServer(('127.0.0.1', 0), functools.partial(Handler, directory=a.directory),
                                             bind_and_activate=False)
    server.socket.close()
    server.socket = socket.socket(fileno=a.fd)
    server.daemon_threads = True
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


if __name__ == '__main__':
    main()
