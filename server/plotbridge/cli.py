"""Command line: `plotbridge serve` and `plotbridge submit`."""

from __future__ import annotations

import argparse
import asyncio
import gc
import logging
import os
import socket
import sys
from pathlib import Path
from typing import Any

from plotbridge import log as logsetup
from plotbridge.config import Config, default_data_dir, find_web_dir

log = logging.getLogger("plotbridge")

WS_MAX_BYTES = 65536  # a larger WebSocket message closes the connection (1009)


def _env(name: str, default: Any = None) -> Any:
    return os.environ.get(f"PLOTBRIDGE_{name}", default)


def _env_flag(name: str) -> bool:
    return str(_env(name, "")).strip().lower() in ("1", "true", "yes", "on")


def add_serve_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default=_env("HOST", "0.0.0.0"), help="address to listen on")
    parser.add_argument("--port", type=int, default=int(_env("PORT", 8000)), help="TCP port")
    parser.add_argument(
        "--data-dir", type=Path, default=Path(_env("DATA_DIR", default_data_dir())),
        help="jobs, database and token (default ~/.local/share/plotbridge)",
    )  # fmt: skip
    link = parser.add_mutually_exclusive_group()
    link.add_argument("--serial", default=_env("SERIAL") or None, help="serial device of a board")
    link.add_argument(
        "--virtual", action="store_true", help="drive the simulated plotter (the default)"
    )
    parser.add_argument("--baud", type=int, default=int(_env("BAUD", 115200)), help="serial baud")
    parser.add_argument(
        "--sim-speed", type=float, default=float(_env("SIM_SPEED", 1.0)),
        help="virtual plotter speed, times real time (0: unthrottled)",
    )  # fmt: skip
    parser.add_argument(
        "--board", default=_env("BOARD", "uno-cnc-shield"),
        help="virtual plotter's board profile (firmware/src/boards/NAME.h)",
    )  # fmt: skip
    parser.add_argument("--token", default=_env("TOKEN"), help="API token (default: generated)")
    parser.add_argument(
        "--max-upload-mb", type=float, default=float(_env("MAX_UPLOAD_MB", 50)),
        help="largest accepted upload, MB",
    )  # fmt: skip
    parser.add_argument(
        "--auto-start", action="store_true", default=_env_flag("AUTO_START"),
        help="start the next queued job automatically",
    )  # fmt: skip
    parser.add_argument(
        "--log-level", default=_env("LOG_LEVEL", "info"), choices=logsetup.LEVELS,
        help="console log level",
    )  # fmt: skip


def config_from_args(args: argparse.Namespace) -> Config:
    serial = None if args.virtual else args.serial
    return Config(
        host=args.host,
        port=args.port,
        data_dir=args.data_dir.expanduser().resolve(),
        serial=serial,
        baud=args.baud,
        sim_speed=args.sim_speed,
        board=args.board,
        token=args.token,
        max_upload_mb=args.max_upload_mb,
        auto_start=args.auto_start,
        log_level=args.log_level,
        web_dir=find_web_dir(),
    )


def _login_url(config: Config, token: str) -> str:
    host = config.host
    if host in ("0.0.0.0", "::", ""):
        host = socket.gethostname()
    return f"http://{host}:{config.port}/login?token={token}"


def keep_pauses_short() -> None:
    """Nothing may stall the event loop for long (an emergency stop waits behind it).

    A full garbage collection walks every object: 15-20 ms with the app loaded,
    so what exists after start-up is frozen out of it. And a worker thread
    (store, program reads) hands the GIL back within 1 ms instead of 5.
    """
    gc.collect()
    gc.freeze()
    sys.setswitchinterval(0.001)


async def serve(config: Config) -> int:
    import uvicorn

    from plotbridge.app import create_app
    from plotbridge.auth import load_or_create_token
    from plotbridge.link import Link

    config.data_dir.mkdir(parents=True, exist_ok=True)
    token = config.token or load_or_create_token(config.data_dir)
    virtual = None
    device = config.serial
    if config.virtual:
        from plotbridge.virtual import VirtualPlotter

        virtual = VirtualPlotter(data_dir=config.data_dir / "sim", speed=config.sim_speed,
                                 board=config.board)
        await virtual.start()
        device = str(virtual.port)
        log.info("virtual plotter on %s (speed %g)", device, config.sim_speed)
    try:
        link = Link(device, config.baud)
        app = create_app(config, link, token, virtual)
        settings = uvicorn.Config(
            app, host=config.host, port=config.port, log_level="warning",
            ws="websockets-sansio", lifespan="on", access_log=False, ws_max_size=WS_MAX_BYTES,
        )  # fmt: skip
        settings.load()  # imports the protocol modules now, before the freeze
        keep_pauses_short()
        server = uvicorn.Server(settings)
        print(f"plotbridge: open {_login_url(config, token)}", flush=True)
        log.info("serving on %s:%d, data in %s", config.host, config.port, config.data_dir)
        await server.serve()
    finally:
        if virtual is not None:
            await virtual.stop()
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(prog="plotbridge", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    add_serve_arguments(commands.add_parser("serve", help="run the server"))
    submit_parser = commands.add_parser("submit", help="upload a drawing to a server")
    if argv[:1] == ["submit"]:  # its client libraries (httpx, rich) stay out of the server
        from plotbridge import submit

        submit.add_arguments(submit_parser)
    args = parser.parse_args(argv)
    if args.command == "submit":
        return submit.run(args)
    logsetup.setup(args.log_level)
    try:
        return asyncio.run(serve(config_from_args(args)))
    except KeyboardInterrupt:
        return 0
    except (RuntimeError, OSError) as exc:  # no virtual plotter, unusable data dir, port taken
        log.error("cannot serve: %s", exc)
        return 1


if __name__ == "__main__":
    sys.exit(main())
