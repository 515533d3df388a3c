"""The server process stays free of the importer's heavy modules (numpy: ~12 MB RSS)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

HEAVY = ("numpy", "svgelements")


def run_python(code: str) -> str:
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_server_modules_and_a_running_job_do_not_import_numpy(tmp_path):
    out = run_python(f"""
        import sys
        from pathlib import Path
        import plotbridge.app, plotbridge.cli, plotbridge.queue
        from plotbridge.app import Board, create_app
        from plotbridge.config import Config
        from plotbridge.jobs.model import Job
        from plotbridge.plotter.link import Link
        from plotbridge.jobs.progress import follow, plan_of

        config = Config(data_dir=Path({str(tmp_path)!r}))
        create_app(config, [Board("p", Link("/dev/null"))], "t" * 16)
        job = Job(id="j", name="j", format="gcode", lines_total=10, lines_done=4,
                  estimate_s=10.0, timeline=[(10, 10.0)])
        follow(job, None, plan_of(job, None, 0), 5, None)  # a running job's eta, as served
        assert job.eta_s == 6.0, job
        print(sorted(m for m in sys.modules if m.split(".")[0] in {HEAVY!r}))
    """)
    assert out == "[]", f"loaded in the server process: {out}"


def test_importing_keeps_its_public_names_loaded_on_first_use():
    out = run_python(f"""
        import sys
        import plotbridge.importing as importing
        import plotbridge.motion.eta
        from plotbridge.importing import eta
        assert callable(eta) and importing.eta is eta  # the function, not its module
        assert not any(m.split(".")[0] in {HEAVY!r} for m in sys.modules)
        names = {{name: getattr(importing, name) for name in importing.__all__}}
        assert set(names) <= set(dir(importing))
        from plotbridge.importing.pipeline import import_file
        assert names["import_file"] is import_file
        print("numpy" in sys.modules)
    """)
    assert out == "True"  # the heavy modules do load once a lazy name is used
    try:
        from plotbridge.importing import no_such_name  # noqa: F401
    except ImportError as exc:
        assert "no_such_name" in str(exc)
    else:
        raise AssertionError("an unknown name must not import")
