"""The live meshcat server, bound to 127.0.0.1 only (run as ``python -m dqlab.viz._server``).

meshcat's own server listens for browsers on every network interface; this one keeps both
its web port and its command port on the loopback interface, prints its two addresses on
standard output (``zmq_url=...`` and ``web_url=...``), and exits by itself when the process
that started it is gone, so that no server outlives its notebook kernel.
"""

import argparse
import os
import sys

HOST = "127.0.0.1"


def _make_bridge():
    import tornado.web
    from meshcat.servers import zmqserver as zs

    class LoopbackApplication(tornado.web.Application):
        def listen(self, port, address=None, **kwargs):
            return super().listen(port, address=HOST, **kwargs)

    class LoopbackBridge(zs.ZMQWebSocketBridge):
        def make_app(self):
            return LoopbackApplication([
                (r"/static/(.*)", zs.StaticFileHandlerNoCache,
                 {"path": zs.VIEWER_ROOT, "default_filename": zs.VIEWER_HTML}),
                (r"/", zs.WebSocketHandler, {"bridge": self}),
            ])

    return LoopbackBridge(host=HOST)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parent-pid", type=int, default=None,
                        help="exit when this process is no longer our parent")
    args = parser.parse_args(argv)

    import tornado.ioloop

    bridge = _make_bridge()
    print(f"zmq_url={bridge.zmq_url}")
    print(f"web_url={bridge.web_url}", flush=True)
    # Nobody reads our output after the addresses: send it nowhere rather than fill a pipe.
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.dup2(devnull, sys.stderr.fileno())

    if args.parent_pid is not None:
        def check_parent():
            if os.getppid() != args.parent_pid:
                tornado.ioloop.IOLoop.current().stop()

        tornado.ioloop.PeriodicCallback(check_parent, 500).start()
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
