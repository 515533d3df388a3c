"""`plotbridge submit`: upload a drawing from a script, optionally start it and follow it."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import httpx
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

END_STATES = {"done", "failed", "cancelled", "stopped", "interrupted"}
PLACEMENT_FIELDS = ("paper", "margin", "fit", "rotate", "scale", "optimize")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    env = os.environ.get
    parser.add_argument("file", type=Path, help="drawing to upload (G-code, SVG, coordinates)")
    parser.add_argument(
        "--server",
        default=env("PLOTBRIDGE_SERVER", "http://127.0.0.1:8000"),
        help="server URL (env PLOTBRIDGE_SERVER)",
    )
    parser.add_argument(
        "--token", default=env("PLOTBRIDGE_TOKEN"), help="API token (env PLOTBRIDGE_TOKEN)"
    )
    parser.add_argument("--name", help="job name (default: the file name)")
    parser.add_argument("--start", action="store_true", help="start the job after upload")
    parser.add_argument("--wait", action="store_true", help="follow the job until it ends")
    parser.add_argument("--json", action="store_true", help="print the job as JSON")
    parser.add_argument("--paper", help="fit onto a paper size: A6..A3, letter (-landscape)")
    parser.add_argument("--margin", type=float, help="paper margin in mm")
    parser.add_argument("--fit", action="store_true", default=None, help="scale to fit")
    parser.add_argument("--rotate", type=int, choices=(0, 90, 180, 270), help="quarter turns")
    parser.add_argument("--scale", type=float, help="scale factor")
    parser.add_argument(
        "--optimize",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="reorder and merge strokes to cut pen-up travel",
    )
    parser.add_argument(
        "--poll", type=float, default=0.5, help="seconds between progress polls with --wait"
    )


class SubmitError(Exception):
    """A failure worth one clear line on stderr."""


def _detail(response: httpx.Response) -> str:
    try:
        detail = response.json().get("detail")
    except ValueError:
        return response.text.strip() or response.reason_phrase
    if isinstance(detail, dict) and "errors" in detail:
        return "\n".join(
            f"  line {e['line']}: {e['message']}" if e.get("line") else f"  {e['message']}"
            for e in detail["errors"]
        )
    return str(detail)


def _check(response: httpx.Response, what: str) -> dict[str, Any]:
    if response.is_error:
        raise SubmitError(f"{what} failed ({response.status_code}):\n{_detail(response)}")
    return response.json()


def upload(client: httpx.Client, args: argparse.Namespace) -> dict[str, Any]:
    fields: dict[str, str] = {"name": args.name or args.file.name}
    for key in PLACEMENT_FIELDS:
        value = getattr(args, key)
        if value is not None:
            fields[key] = str(value).lower() if isinstance(value, bool) else str(value)
    with args.file.open("rb") as fh:
        response = client.post("/api/jobs", data=fields, files={"file": (args.file.name, fh)})
    return _check(response, "upload")


def follow(client: httpx.Client, job: dict[str, Any], poll: float, quiet: bool) -> dict[str, Any]:
    console = Console(stderr=True)
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=console, disable=quiet) as progress:
        bar = progress.add_task(job["name"], total=1.0)
        while job["state"] not in END_STATES:
            time.sleep(poll)
            job = _check(client.get(f"/api/jobs/{job['id']}"), "status")
            progress.update(
                bar, completed=job["progress"], description=f"{job['name']} [{job['state']}]"
            )
    return job


def run(args: argparse.Namespace) -> int:
    err = Console(stderr=True)
    if not args.file.is_file():
        err.print(f"plotbridge submit: no such file: {args.file}")
        return 2
    if not args.token:
        err.print("plotbridge submit: no token: pass --token or set PLOTBRIDGE_TOKEN")
        return 2
    headers = {"Authorization": f"Bearer {args.token}"}
    try:
        with httpx.Client(base_url=args.server, headers=headers, timeout=120) as client:
            job = upload(client, args)
            if args.start:
                job = _check(client.post(f"/api/jobs/{job['id']}/start"), "start")
            if args.wait:
                job = follow(client, job, args.poll, quiet=args.json)
    except SubmitError as exc:
        err.print(f"plotbridge submit: {exc}", markup=False, highlight=False)
        return 1
    except httpx.HTTPError as exc:
        err.print(f"plotbridge submit: cannot reach {args.server}: {exc}")
        return 1
    if args.json:
        print(json.dumps(job, indent=2))
    else:
        estimate = job.get("estimate_s") or 0
        print(f"job {job['id']} '{job['name']}': {job['state']} (estimate {estimate:.0f} s)")
    if args.wait and job["state"] != "done":
        if job.get("error"):
            err.print(f"plotbridge submit: {job['error']}", markup=False)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="plotbridge submit")
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
