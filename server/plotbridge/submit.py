"""`plotbridge submit`: upload a drawing from a script, optionally start it and follow it."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from plotbridge.client import Plotbridge, PlotbridgeError
from plotbridge.commands import add_connection_arguments, connect, fail
from plotbridge.progress import job_progress

PLACEMENT_FIELDS = ("paper", "margin", "fit", "rotate", "scale", "optimize")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", type=Path, help="drawing to upload (G-code, SVG, coordinates)")
    add_connection_arguments(parser)
    parser.add_argument("--name", help="job name (default: the file name)")
    parser.add_argument("--plotter", help="plotter to run it on (default: any)")
    parser.add_argument("--start", action="store_true", help="start the job after upload")
    parser.add_argument("--fleet", action="store_true",
                        help="send it to the MQTT fleet's queue: the first free plotter of any "
                             "bridge whose work area fits it")
    parser.add_argument("--wait", action="store_true", help="follow the job until it ends")
    parser.add_argument("--paper", help="fit onto a paper size: A6..A3, letter (-landscape)")
    parser.add_argument("--margin", type=float, help="paper margin in mm")
    parser.add_argument("--fit", action="store_true", default=None, help="scale to fit")
    parser.add_argument("--rotate", type=int, choices=(0, 90, 180, 270), help="quarter turns")
    parser.add_argument("--scale", type=float, help="scale factor")
    parser.add_argument(
        "--layers", help="layers to plot, comma-separated: numbers (1,3: the job's layers, "
        "with --start) or SVG layer labels, ids or stroke colours (only those are imported)",
    )  # fmt: skip
    parser.add_argument(
        "--pen", action="append", default=[], metavar="LAYER=PEN", type=layer_pen,
        help="the pen (name or id in the pen library) for a layer (number or name); repeat",
    )  # fmt: skip
    parser.add_argument(
        "--optimize", action=argparse.BooleanOptionalAction, default=None,
        help="reorder and merge strokes to cut pen-up travel",
    )  # fmt: skip
    parser.add_argument(
        "--poll", type=float, default=0.5, help="seconds between progress polls with --wait"
    )


def layer_pen(text: str) -> tuple[str, str]:
    """`--pen LAYER=PEN`."""
    layer, sep, pen = text.partition("=")
    if not sep or not layer.strip() or not pen.strip():
        raise argparse.ArgumentTypeError(f"expected LAYER=PEN (e.g. 2='fineliner'), got {text!r}")
    return layer.strip(), pen.strip()


def send(pb: Plotbridge, args: argparse.Namespace) -> dict[str, Any]:
    placement = {key: getattr(args, key) for key in PLACEMENT_FIELDS}
    layers = [p.strip() for p in args.layers.split(",") if p.strip()] if args.layers else None
    numbers = [int(p) for p in layers] if layers and all(p.isdecimal() for p in layers) else None
    pens: dict[str, str | int | None] = dict(args.pen)
    job = pb.upload(args.file, name=args.name, layers=None if numbers else layers,
                    plotter=args.plotter, pens=pens or None, fleet=args.fleet,
                    **placement)  # fmt: skip
    if args.start:
        job = pb.start(job["id"], layers=numbers)
    if args.wait:
        with job_progress(job["name"], quiet=args.json) as update:
            if args.fleet:
                return {**job, "fleet": pb.wait_fleet(job["fleet"]["id"], update, poll=args.poll)}
            job = pb.wait(job["id"], update, poll=args.poll)
    return job


def run(args: argparse.Namespace) -> int:
    if not args.file.is_file():
        print(f"plotbridge submit: no such file: {args.file}", file=sys.stderr)
        return 2
    if args.layers and all(p.strip().isdecimal() for p in args.layers.split(",") if p.strip()) \
            and not args.start:
        print("plotbridge submit: --layers with numbers picks the layers a start plots: "
              "add --start", file=sys.stderr)  # fmt: skip
        return 2
    if args.fleet and (args.start or args.plotter):
        print("plotbridge submit: --fleet lets the fleet pick the plotter and start it: "
              "drop --start and --plotter", file=sys.stderr)  # fmt: skip
        return 2
    try:
        with connect(args) as pb:
            job = send(pb, args)
    except PlotbridgeError as exc:
        return fail("submit", exc)
    placed = job["fleet"] if args.fleet and args.wait else None  # where the fleet ran it
    if args.json:
        print(json.dumps(job, indent=2))
    elif placed is not None:
        print(f"job {job['id']} '{job['name']}': {placed['state']} on "
              f"{placed['bridge']}/{placed['plotter']} (the fleet's job {placed['id']})")
    else:
        estimate = job.get("estimate_s") or 0
        where = " in the fleet's queue" if job.get("fleet") else ""
        print(f"job {job['id']} '{job['name']}': {job['state']}{where} "
              f"(estimate {estimate:.0f} s)")
    if args.wait and (placed or job)["state"] != "done":
        if job.get("error"):
            print(f"plotbridge submit: {job['error']}", file=sys.stderr)
        return 1
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="plotbridge submit")
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
