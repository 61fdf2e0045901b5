"""``bikerider serve``: a local web page for a bicycle's dynamics and the gap diagnosis (docs/app.md)."""

from __future__ import annotations

import argparse


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "serve",
        help="a local web page: a bicycle's parameters and dynamics, updated on every edit, and the gap diagnosis",
        description=(
            "Serve a local web page (standard library HTTP server; the browser draws the figures; nothing "
            "is downloaded): choose a shipped bicycle or upload files as estimate and benchmark read them, "
            "edit the benchmark parameters and their sigmas (the front assembly also in the steer-axis "
            "frame), see the eigenvalues against speed with the self-stable band and the uncertainty band, "
            "weave and capsize speeds with sigmas, the side view, mode shapes and Bode at a chosen speed, "
            "a stability map and the closed loop under constant steer-torque gains; upload a model and "
            "records to run the gap diagnosis; download parameters, tables, figures and the report. See "
            "docs/app.md."
        ),
    )
    p.add_argument("--port", type=int, default=8050, help="port to listen on (default 8050; 0: any free port)")
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to bind (default 127.0.0.1: this computer only; another address exposes the page "
        "and its uploads to the network)",
    )
    p.add_argument("--open", action="store_true", help="open the page in the default web browser")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    # The page's modules import NumPy and the model: imported when the command runs.
    import signal
    import webbrowser

    from bikerider.app.server import App, make_server
    from bikerider.diagnose import diagnose_files
    from bikerider.errors import InputError

    if not 0 <= args.port <= 65535:
        raise InputError("--port", args.port, "a port number from 0 to 65535")
    app = App(diagnose=lambda model, data, experiment: diagnose_files(model, data, experiment))
    server = make_server(app, args.host, args.port)
    host, port = server.server_address[:2]
    shown = f"[{host}]" if ":" in str(host) else host
    url = f"http://{shown}:{port}/"
    print(f"bikerider serve: the page is at {url} (Ctrl+C stops it)", flush=True)
    if args.host not in ("127.0.0.1", "localhost", "::1"):
        print(f"bikerider serve: note: bound to {args.host}: other computers can reach the page", flush=True)
    if args.open:
        webbrowser.open(url)

    def stop(signum, frame):  # SIGTERM stops the page as Ctrl+C does: the uploads are removed
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.server_close()
        app.close()
    return 0
