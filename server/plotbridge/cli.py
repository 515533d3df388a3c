"""Command line: `plotbridge serve`, and the client verbs (submit, status, queue, stop,
pause, resume, home) built on `plotbridge.client`."""

from __future__ import annotations

import argparse
import asyncio
import gc
import logging
import math
import os
import sys
from pathlib import Path
from typing import Any

from plotbridge import log as logsetup
from plotbridge.config import (
    PLOTTERS_FILE,
    Config,
    ConfigError,
    PlotterConfig,
    check_names,
    default_data_dir,
    find_web_dir,
    read_plotters_file,
)
from plotbridge.jobs.model import AFTER_JOB
from plotbridge.mqtt import settings as mqtt_settings
from plotbridge.people import cli as people_cli
from plotbridge.people.cli import LISTEN_FILE, listening_port

log = logging.getLogger("plotbridge")

WS_MAX_BYTES = 65536  # a larger WebSocket message closes the connection (1009)
SHUTDOWN_GRACE_S = 5  # s a stopping server lets requests in flight finish (an upload waiting
#   for an import would otherwise hold the stop off for as long as the import takes)


def _env(name: str, default: Any = None) -> Any:
    return os.environ.get(f"PLOTBRIDGE_{name}", default)


def _env_flag(name: str) -> bool:
    return str(_env(name, "")).strip().lower() in ("1", "true", "yes", "on")


def _point(text: str) -> tuple[float, float]:
    """`X,Y` in mm."""
    try:
        x, y = (float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y in mm, got {text!r}") from None
    if not all(math.isfinite(v) and v >= 0 for v in (x, y)):
        raise argparse.ArgumentTypeError(f"X,Y must be finite and not negative, got {text!r}")
    return x, y


def _ranged(kind: type, low: float, high: float) -> Any:
    """An argparse type: a finite `kind` number from `low` to `high`."""

    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not (math.isfinite(value) and low <= value <= high):
            raise argparse.ArgumentTypeError(f"{text!r}: a finite number from {low:g} to {high:g}")
        return value

    parse.__name__ = kind.__name__  # argparse names the type in its messages
    return parse


def _board(text: str) -> str:
    """A board profile's name (firmware/src/boards/NAME.h), checked before anything runs."""
    from plotbridge.profiles import UnknownBoard, check_board

    try:
        return check_board(text)
    except UnknownBoard as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _webhook_url(text: str) -> str:
    """An http(s) URL to post events to."""
    from plotbridge.notify import check_url

    try:
        return check_url(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def add_serve_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default=_env("HOST", "0.0.0.0"), help="address to listen on")
    parser.add_argument("--port", type=_ranged(int, 1, 65535), default=_env("PORT", "8000"),
                        help="TCP port")
    parser.add_argument(
        "--data-dir", type=Path, default=Path(_env("DATA_DIR", default_data_dir())),
        help="jobs, database and token (default ~/.local/share/plotbridge)",
    )  # fmt: skip
    link = parser.add_mutually_exclusive_group()
    link.add_argument(
        "--serial", action="append", default=None, metavar="DEVICE",
        help="serial device of a board; repeat for several plotters",
    )  # fmt: skip
    link.add_argument(
        "--virtual", nargs="?", type=int, const=1, default=None, metavar="N",
        help="drive N simulated plotters (default: 1; the default without --serial)",
    )  # fmt: skip
    parser.add_argument("--baud", type=_ranged(int, 300, 4_000_000), default=_env("BAUD", "115200"),
                        help="serial baud")
    parser.add_argument(
        "--sim-speed", type=_ranged(float, 0, 1000), default=_env("SIM_SPEED", "1"),
        help="virtual plotter speed, times real time (0: unthrottled)",
    )  # fmt: skip
    parser.add_argument(
        "--board", type=_board, default=_env("BOARD", "uno-cnc-shield"),
        help="board profile of the plotters (firmware/src/boards/NAME.h); "
             "a virtual plotter runs that board's firmware build",
    )  # fmt: skip
    parser.add_argument(
        "--token", help="API token, at least 16 characters; visible in `ps`, so prefer "
        "--token-file or PLOTBRIDGE_TOKEN (default: generated into DATA_DIR/token)",
    )  # fmt: skip
    parser.add_argument(
        "--token-file", type=Path, default=_env("TOKEN_FILE"),
        help="read the API token from this file (re-read when it changes)",
    )  # fmt: skip
    parser.add_argument(
        "--allowed-host", action="append", default=[
            n for n in str(_env("ALLOWED_HOSTS", "")).split(",") if n.strip()
        ], help="a further Host name to serve (beside this machine's names and addresses)",
    )  # fmt: skip
    parser.add_argument(
        "--client-connections", type=_ranged(int, 1, 10_000),
        default=_env("CLIENT_CONNECTIONS", "32"),
        help="open connections one client address may hold (503 beyond)",
    )  # fmt: skip
    parser.add_argument(
        "--max-upload-mb", type=_ranged(float, 0.001, 100_000),
        default=_env("MAX_UPLOAD_MB", "50"),
        help="largest accepted upload, MB",
    )  # fmt: skip
    imports = parser.add_argument_group("import limits")
    for flag, kind, default, high, what in IMPORT_LIMITS:
        imports.add_argument(
            f"--{flag}", type=_ranged(kind, 1, high),
            default=str(_env(flag.upper().replace("-", "_"), default)), help=what,
        )  # fmt: skip
    parser.add_argument(
        "--auto-start", action="store_true", default=_env_flag("AUTO_START"),
        help="start the next queued job automatically",
    )  # fmt: skip
    parser.add_argument(
        "--home-on-connect", action="store_true", default=_env_flag("HOME_ON_CONNECT"),
        help="home ($H) a plotter that connects in Alarm (for plotters with limit switches)",
    )  # fmt: skip
    parser.add_argument(
        "--after-job", choices=AFTER_JOB, default=_env("AFTER_JOB", "none"),
        help="what a plotter does once a job is done, unless the job says: "
             "park (pen up, carriage to --park), home, none (default)",
    )  # fmt: skip
    parser.add_argument(
        "--park", type=_point, default=_env("PARK", "0,0"), metavar="X,Y",
        help="park position in mm (default 0,0: the front left corner)",
    )  # fmt: skip
    parser.add_argument(
        "--webhook", action="append", type=_webhook_url, metavar="URL",
        default=[u for u in str(_env("WEBHOOKS", "")).split(",") if u.strip()],
        help="POST job and plotter events as JSON to URL (repeatable; env PLOTBRIDGE_WEBHOOKS "
             "comma-separated; more in the settings)",
    )  # fmt: skip
    parser.add_argument(
        "--webhook-allow-local", action="store_true", default=_env_flag("WEBHOOK_ALLOW_LOCAL"),
        help="let webhook URLs from the settings reach this machine or link-local addresses",
    )  # fmt: skip
    parser.add_argument(
        "--zeroconf", action=argparse.BooleanOptionalAction,
        default=str(_env("ZEROCONF", "1")).strip().lower() not in ("0", "false", "no", "off"),
        help="announce the server on the LAN by mDNS (default on; env PLOTBRIDGE_ZEROCONF=0)",
    )  # fmt: skip
    parser.add_argument(
        "--log-level", default=_env("LOG_LEVEL", "info"), choices=logsetup.LEVELS,
        help="console log level",
    )  # fmt: skip
    mqtt_settings.add_arguments(parser)


IMPORT_LIMITS = (  # flag, type, default, most, help: the defaults keep a 2 GB Pi 4 responsive
    ("import-workers", int, 2, 64, "import worker processes (one stays free for small uploads)"),
    ("import-time-limit", float, 120.0, 86_400, "seconds one import may take"),
    ("import-memory-mb", int, 512, 1 << 20, "memory (address space) one import may use, MB"),
    ("job-quota-mb", float, 200.0, 1 << 30, "disk space one job's files may take, MB"),
    ("total-quota-mb", float, 2048.0, 1 << 30, "disk space all jobs' files may take, MB"),
)


def plotters_from_args(args: argparse.Namespace, data_dir: Path) -> list[PlotterConfig]:
    """--serial (repeatable), --virtual N, else the data directory's plotters.toml, else
    PLOTBRIDGE_SERIAL (devices separated by commas), else one virtual plotter."""
    serial = args.serial
    if serial is None and args.virtual is None:
        if (data_dir / PLOTTERS_FILE).exists():
            return read_plotters_file(data_dir / PLOTTERS_FILE)
        serial = [d for d in str(_env("SERIAL", "")).split(",") if d.strip()] or None
    if serial:
        plotters = [PlotterConfig(f"plotter{n}", d.strip(), board=args.board, baud=args.baud)
                    for n, d in enumerate(serial, 1)]  # fmt: skip
    else:
        count = 1 if args.virtual is None else args.virtual
        if count < 1 or count > 16:
            raise ConfigError(f"--virtual {count}: between 1 and 16 virtual plotters")
        plotters = [PlotterConfig(f"plotter{n}", board=args.board) for n in range(1, count + 1)]
    return check_names(plotters, "the command line")


def webhooks_from_args(args: argparse.Namespace) -> tuple[str, ...]:
    """--webhook URLs (checked by argparse) and PLOTBRIDGE_WEBHOOKS' (checked here)."""
    from plotbridge.notify import check_urls

    try:
        return tuple(check_urls(args.webhook))
    except ValueError as exc:
        raise ConfigError(f"--webhook / PLOTBRIDGE_WEBHOOKS: {exc}") from None


def config_from_args(args: argparse.Namespace) -> Config:
    from plotbridge.importing.workers import Limits

    data_dir = args.data_dir.expanduser().resolve()
    return Config(
        host=args.host,
        port=args.port,
        data_dir=data_dir,
        plotters=plotters_from_args(args, data_dir),
        sim_speed=args.sim_speed,
        token=args.token,
        token_file=args.token_file.expanduser().resolve() if args.token_file else None,
        allowed_hosts=tuple(args.allowed_host),
        client_connections=args.client_connections,
        max_upload_mb=args.max_upload_mb,
        auto_start=args.auto_start,
        home_on_connect=args.home_on_connect,
        after_job=args.after_job,
        park=args.park,
        webhooks=webhooks_from_args(args),
        webhook_allow_local=args.webhook_allow_local,
        log_level=args.log_level,
        zeroconf=args.zeroconf,
        web_dir=find_web_dir(),
        mqtt=mqtt_settings.from_args(args, data_dir, args.port),
        import_limits=Limits(
            workers=max(1, args.import_workers), time_limit=args.import_time_limit,
            memory_mb=args.import_memory_mb, job_quota_mb=args.job_quota_mb,
            total_quota_mb=args.total_quota_mb,
        ),
    )


def _stdout_is_journal() -> bool:
    """Standard output is systemd's journal (JOURNAL_STREAM names its device:inode; a child
    that inherited the variable with its output elsewhere is not)."""
    try:
        st = os.fstat(sys.stdout.fileno())
    except (OSError, ValueError):
        return False
    return os.environ.get("JOURNAL_STREAM") == f"{st.st_dev}:{st.st_ino}"


def print_login(host: str, port: int, data_dir: Path) -> None:
    """A one-time login link for the token's admin and its QR code, on the console (never
    the token itself in a URL: the link becomes a session once opened)."""
    people_cli.print_token_link(data_dir.expanduser(), host, port)


def resolve_token(config: Config) -> tuple[str, bool]:
    """The token and whether it was just generated. Sources, first found: --token
    (warned: it shows in `ps`), --token-file, PLOTBRIDGE_TOKEN, DATA_DIR/token."""
    from plotbridge.auth import check_token_rules, load_or_create_token, read_token_file

    if config.token:
        log.warning("--token shows in `ps` to every user; use --token-file or PLOTBRIDGE_TOKEN")
        return check_token_rules(config.token), False
    if config.token_file is not None:
        return read_token_file(config.token_file), False
    if _env("TOKEN"):
        return check_token_rules(_env("TOKEN")), False
    config.token_file = config.data_dir / "token"
    return load_or_create_token(config.token_file)


def private_data_dir(path: Path) -> None:
    """Data directory 0700; everything the server creates in it 0600/0700 (umask)."""
    os.umask(0o077)
    path.mkdir(parents=True, exist_ok=True, mode=0o700)
    path.chmod(0o700)


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

    from plotbridge import mdns
    from plotbridge.app import Board, create_app
    from plotbridge.guard import connections, wsingress
    from plotbridge.plotter.link import Link
    from plotbridge.plotter.plotter import WorkArea
    from plotbridge.virtual import VirtualPlotter

    private_data_dir(config.data_dir)
    token, generated = resolve_token(config)
    file_limit = connections.raise_file_limit()
    connections.configure(config.client_connections, file_limit)
    boards: list[Board] = []
    try:
        for index, plotter in enumerate(config.plotters):
            area = WorkArea(*plotter.work_area) if plotter.work_area else None
            virtual = None
            device = plotter.device
            if device is None:
                virtual = VirtualPlotter(data_dir=sim_dir(config, index, plotter.name),
                                         speed=config.sim_speed,
                                         board=plotter.board or "uno-cnc-shield")
                await virtual.start()
                device = str(virtual.port)
                log.info("%s: virtual plotter on %s (speed %g)", plotter.name, device,
                         config.sim_speed)  # fmt: skip
            boards.append(Board(plotter.name, Link(device, plotter.baud), virtual, area,
                                plotter.board))
        app = create_app(config, boards, token)
        settings = uvicorn.Config(
            app, host=config.host, port=config.port, log_level="warning", log_config=None,
            ws=wsingress.MeteredWebSocket, ws_max_size=WS_MAX_BYTES, lifespan="on",
            access_log=False,
            ws_per_message_deflate=False,  # a 64 KiB frame of one byte repeated comes in as 100
            # bytes and cost the loop its decompression; the compression of every event too
            http=connections.GuardedH11, h11_max_incomplete_event_size=connections.MAX_HEADER_BYTES,
            timeout_keep_alive=5, backlog=connections.BACKLOG,
            timeout_graceful_shutdown=SHUTDOWN_GRACE_S,
        )  # fmt: skip
        settings.load()  # imports the protocol modules now, before the freeze
        keep_pauses_short()
        server = connections.GuardedServer(settings)
        (config.data_dir / LISTEN_FILE).write_text(f"{config.host} {config.port}\n")
        if generated and _stdout_is_journal():  # a service: the journal is readable
            #   by more than the token's owner, so the link stays out of it
            log.info("a new token is in %s; `plotbridge token --data-dir %s` prints the "
                     "login link", config.token_file, config.data_dir)
        elif generated:  # later starts keep it out of logs: `plotbridge token` prints one
            print_login(config.host, config.port, config.data_dir)
        log.info(
            "serving on %s:%d, data in %s, open-file limit %d, plotters: %s",
            config.host, config.port, config.data_dir, file_limit,
            ", ".join(p.name for p in config.plotters),
        )  # fmt: skip
        async with mdns.announced(config.host, config.port, config.zeroconf):
            await server.serve()
    finally:
        for board in boards:
            if board.virtual is not None:
                await board.virtual.stop()
    return 0


def sim_dir(config: Config, index: int, name: str) -> Path:
    """A virtual plotter's files: `sim/` for the first (where a single-plotter server
    kept them, so its EEPROM settings stay), `sim-NAME/` for the others."""
    return config.data_dir / ("sim" if index == 0 else f"sim-{name}")


def add_token_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--data-dir", type=Path, default=Path(_env("DATA_DIR", default_data_dir())),
        help="the server's data directory (its token file is DATA_DIR/token)",
    )  # fmt: skip
    parser.add_argument("--token-file", type=Path, default=_env("TOKEN_FILE"),
                        help="the server's --token-file instead")  # fmt: skip
    parser.add_argument("--rotate", action="store_true",
                        help="write a new token: every session ends (a running server notices)")
    parser.add_argument("--host", default=_env("HOST", "0.0.0.0"), help="host in the link")
    parser.add_argument("--port", type=int, default=None,
                        help="link's port (default: the running server's, else 8000)")


def token_command(args: argparse.Namespace) -> int:
    from plotbridge.auth import TokenRefused, load_or_create_token, new_token, write_private

    path = args.token_file or args.data_dir.expanduser() / "token"
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        if args.rotate:
            write_private(path, new_token() + "\n")
            print(f"plotbridge: new token in {path}; every session of the token has ended",
                  flush=True)  # fmt: skip
        else:
            load_or_create_token(path)
    except (OSError, TokenRefused) as exc:
        print(f"plotbridge token: {exc}", file=sys.stderr)
        return 1
    port = args.port if args.port is not None else listening_port(args.data_dir.expanduser())
    print_login(args.host, port, args.data_dir)
    return 0


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(prog="plotbridge", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    add_serve_arguments(commands.add_parser("serve", help="run the server"))
    token_parser = commands.add_parser("token", help="print the login link, or --rotate the token")
    add_token_arguments(token_parser)
    submit_parser = commands.add_parser("submit", help="upload a drawing to a server")
    people_cli.add_commands(commands, Path(_env("DATA_DIR", default_data_dir())))
    if argv[:1] != ["serve"]:  # the client modules stay out of the server's process
        from plotbridge import commands as verbs
        from plotbridge import submit

        submit.add_arguments(submit_parser)
        verbs.add_verbs(commands)
    args = parser.parse_args(argv)
    if args.command == "submit":
        return submit.run(args)
    if args.command == "token":
        return token_command(args)
    if args.command in ("keys", "users"):
        return people_cli.run(args)
    if args.command != "serve":
        return verbs.run(args)
    logsetup.setup(args.log_level)
    try:
        return asyncio.run(serve(config_from_args(args)))
    except KeyboardInterrupt:
        return 0
    except (RuntimeError, OSError, ConfigError) as exc:  # no simulator, bad config, port taken
        log.error("cannot serve: %s", exc)
        return 1


if __name__ == "__main__":
    sys.exit(main())
