#!/usr/bin/env python3
"""serve.py - the static file server `crowdbake view` runs: Python's http.server on a socket the
command has already bound to 127.0.0.1 (so it knows and prints the port before this starts).

  python3 cli/viewer/serve.py --fd N --directory SITE

Serves SITE (links followed) until Ctrl-C, then exits 0. Requests are not logged; errors are.
A local server only: a request whose Host is not this server's own address (127.0.0.1, localhost
or [::1] with its port) gets 403, so a web page the user visits cannot read the site through DNS
rebinding (its name made to point at 127.0.0.1); and a folder gets 404, not a listing."""
import argparse
import functools
import http.server
import os
import socket
import sys

LOCAL_NAMES = ('127.0.0.1', 'localhost', '[::1]')


class Handler(http.server.SimpleHTTPRequestHandler):
    extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map,
                      '.mjs': 'text/javascript', '.js': 'text/javascript', '.glsl': 'text/plain',
                      '.json': 'application/json', '.pal': 'application/octet-stream',
                      '.exr': 'application/octet-stream', '.glb': 'model/gltf-binary'}

    def parse_request(self):
        if not super().parse_request():
            return False
        port = self.server.server_address[1]
        host = (self.headers.get('Host') or '').strip().lower()
        if host in ['%s:%d' % (name, port) for name in LOCAL_NAMES]:
            return True
        self.refuse(403, "Host '%s' is not this server: open http://127.0.0.1:%d/viewer/viewer.html" % (host[:100], port))
        return False

    def send_head(self):
        if os.path.isdir(self.translate_path(self.path)):
            self.refuse(404, 'no listing of folders: open /viewer/viewer.html')
            return None
        return super().send_head()

    def refuse(self, code, line):
        """A one-line plain-text answer, the connection closed after it."""
        body = ('crowdbake view: %s\n' % line).encode('utf-8', 'replace')
        self.close_connection = True
        self.send_response(code)
        self.send_header('Content-Type', 'text/plain; charset=utf-8')
        self.send_header('Content-Length', str(len(body)))
        self.send_header('Connection', 'close')
        self.end_headers()
        if self.command != 'HEAD':
            self.wfile.write(body)

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
    server.server_address = server.socket.getsockname()[:2]  # the port Host must name
    server.daemon_threads = True
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()


if __name__ == '__main__':
    main()
