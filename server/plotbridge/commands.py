"""The command line's client verbs: status, queue, stop, pause, resume, act, home (and
the connection options `submit` shares), each a thin layer over `plotbridge.client`.
A job is shown with the server's own numbers and words (progress, eta_s, summary) and
the actions it allows now."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from typing import Any

from plotbridge.client import Plotbridge, PlotbridgeError, SetupError

Verb = Callable[[Plotbridge, argparse.Namespace], tuple[Any, str]]


def add_connection_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--url", "--server", dest="url",
        help="server URL (env PLOTBRIDGE_URL; default: the server found on the LAN)",
    )  # fmt: skip
    parser.add_argument("--token", help="API token (env PLOTBRIDGE_TOKEN)")
    parser.add_argument(
        "--token-file", help="file holding the token (env PLOTBRIDGE_TOKEN_FILE)"
    )
    parser.add_argument("--json", action="store_true", help="print the answer as JSON")


def connect(args: argparse.Namespace) -> Plotbridge:
    return Plotbridge(args.url, args.token, token_file=args.token_file)


def fail(verb: str, exc: PlotbridgeError) -> int:
    """One clear message on stderr; exit status 2 for a setup problem, else 1."""
    print(f"plotbridge {verb}: {exc}", file=sys.stderr)
    return 2 if isinstance(exc, SetupError) else 1


def _machine_line(name: str | None, machine: dict[str, Any]) -> str:
    position = machine.get("position") or {}
    where = f"x {position.get('x', 0):.2f} y {position.get('y', 0):.2f}"
    label = f"{name}: " if name else ""
    return f"{label}{machine.get('state')} at {where}, pen {machine.get('pen')}"


def _job_line(job: dict[str, Any]) -> str:
    progress = f"{100 * (job.get('progress') or 0):.0f}%"
    eta = job.get("eta_s")
    left = f", {eta:.0f} s left" if eta else ""
    said = job.get("summary") or job["state"]
    actions = ", ".join(job.get("actions", [])) or "none now"
    return (f"{job['id']}  {job['state']:<11} {progress:>4}{left}  {job['name']}\n"
            f"    {said}; actions: {actions}")


def status(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    plotters = pb.plotters()
    if args.plotter:
        plotters = [p for p in plotters if p.get("name") == args.plotter] or [
            {"name": args.plotter, "machine": pb.machine(args.plotter)}
        ]
    active = pb.active_jobs()
    lines = [f"plotbridge at {pb.url}"]
    lines += [_machine_line(p.get("name"), p.get("machine") or {}) for p in plotters]
    lines += [f"job {_job_line(job)}" for job in active] or ["no job running"]
    answer = {"url": pb.url, "plotters": plotters, "job": active[0] if active else None,
              "jobs": active}  # fmt: skip
    return answer, "\n".join(lines)


def queue(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    jobs = pb.jobs()
    return jobs, "\n".join(_job_line(job) for job in jobs) if jobs else "the queue is empty"


def stop(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    answer = pb.stop(args.plotter, all=args.all)
    return answer, "stopped" + (" every plotter" if args.all else "")


def pause(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    job = pb.pause(args.job)
    return job, f"job {job['id']} {job['state']}"


def resume(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    job = pb.resume(args.job)
    return job, f"job {job['id']} {job['state']}"


def act(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    body = {"reason": args.reason} if args.reason is not None else None
    job = pb.act(args.job, args.action, args.plotter, body)
    return job, f"job {_job_line(job)}"


def home(pb: Plotbridge, args: argparse.Namespace) -> tuple[Any, str]:
    answer = pb.home(args.plotter)
    return answer, _machine_line(args.plotter, answer["machine"])


VERBS: dict[str, tuple[Verb, str]] = {
    "status": (status, "the machine state and the running job"),
    "queue": (queue, "the jobs in queue order"),
    "stop": (stop, "emergency stop, at once"),
    "pause": (pause, "pause the running job (or JOB)"),
    "resume": (resume, "continue the held job (or JOB), or resume a stopped one"),
    "act": (act, "do one of a job's actions (as `plotbridge queue` lists them)"),
    "home": (home, "run the homing cycle"),
}


def add_verbs(commands: argparse._SubParsersAction) -> None:
    for verb, (_, summary) in VERBS.items():
        parser = commands.add_parser(verb, help=summary, description=summary)
        add_connection_arguments(parser)
        if verb in ("pause", "resume"):
            parser.add_argument("job", nargs="?", help="job id (default: the active job)")
        elif verb == "act":
            parser.add_argument("job", help="job id")
            parser.add_argument("action", help="start, hold, continue, stop, resume, "
                                "home_then_resume, restart, cancel, frame, approve, decline")
            parser.add_argument("--plotter", help="the plotter to run it on (start, resume)")
            parser.add_argument("--reason", help="decline: why (the sender sees it)")
        else:
            parser.add_argument("--plotter", help="plotter name (default: the first)")
        if verb == "stop":
            parser.add_argument("--all", action="store_true", help="stop every plotter")


def run(args: argparse.Namespace) -> int:
    verb, _ = VERBS[args.command]
    try:
        with connect(args) as pb:
            answer, text = verb(pb, args)
    except PlotbridgeError as exc:
        return fail(args.command, exc)
    print(json.dumps(answer, indent=2) if args.json else text)
    return 0
