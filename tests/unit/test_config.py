"""Which plotters a server drives: command line and the plotters.toml file."""

from __future__ import annotations

import pytest
from plotbridge.cli import plotters_from_args
from plotbridge.config import ConfigError, PlotterConfig, read_plotters_file

from tests.fixtures.fake_app import serve_args


def test_serial_repeats_and_virtual_counts(tmp_path, monkeypatch):
    monkeypatch.delenv("PLOTBRIDGE_SERIAL", raising=False)
    monkeypatch.delenv("PLOTBRIDGE_BOARD", raising=False)
    two = plotters_from_args(serve_args("--serial", "/dev/a", "--serial", "/dev/b"), tmp_path)
    assert [(p.name, p.device) for p in two] == [("plotter1", "/dev/a"), ("plotter2", "/dev/b")]
    assert [p.name for p in plotters_from_args(serve_args("--virtual", "3"), tmp_path)] == [
        "plotter1", "plotter2", "plotter3"]
    default = PlotterConfig("plotter1", board="uno-cnc-shield")
    assert plotters_from_args(serve_args(), tmp_path) == [default]
    ramps = plotters_from_args(serve_args("--board", "mega-ramps14"), tmp_path)
    assert ramps[0].board == "mega-ramps14"
    with pytest.raises(ConfigError, match="between 1 and 16"):
        plotters_from_args(serve_args("--virtual", "0"), tmp_path)


def test_plotters_file(tmp_path, monkeypatch):
    monkeypatch.delenv("PLOTBRIDGE_SERIAL", raising=False)
    (tmp_path / "plotters.toml").write_text(
        '[[plotter]]\nname = "left"\ndevice = "/dev/ttyUSB0"\nbaud = 9600\n'
        'board = "uno-uln2003"\nwidth = 200\nheight = 150\n\n'
        '[[plotter]]\nname = "sim"\nvirtual = true\n'
    )
    left, sim = plotters_from_args(serve_args(), tmp_path)
    assert left == PlotterConfig("left", "/dev/ttyUSB0", "uno-uln2003", 9600, (200.0, 150.0))
    assert sim.virtual and sim.name == "sim"
    assert plotters_from_args(serve_args("--virtual", "1"), tmp_path)[0].name == "plotter1"


@pytest.mark.parametrize("text, message", [
    ("[[plotter]]\nname = 'x'\n", "needs device"),
    ("[[plotter]]\nvirtual = true\ndevice = '/dev/a'\n", "either device or virtual"),
    ("[[plotter]]\nvirtual = true\nwidth = 100\n", "width and height"),
    ("[[plotter]]\nvirtual = true\ncolour = 'red'\n", "unknown keys colour"),
    ("[[plotter]]\nvirtual = true\n[[plotter]]\nvirtual = true\nname = 'plotter1'\n", "differ"),
    ("[[plotter]]\nvirtual = true\nname = 'a b'\n", "letters, digits"),
    ("[[plotter]\n", "plotters.toml"),
    ("title = 'no plotters'\n", "no [[plotter]]"),
])  # fmt: skip
def test_bad_plotters_file_says_what_and_where(tmp_path, text, message):
    path = tmp_path / "plotters.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=r"plotters\.toml") as info:
        read_plotters_file(path)
    assert message in str(info.value)


SHELL = "$(shell touch {marker})"


@pytest.mark.parametrize("text, key, message", [
    ("[[plotter]]\nvirtual = true\nboard = '{shell}'\n", "board", "unknown board"),
    ("[[plotter]]\nvirtual = true\nwidth = inf\nheight = 100\n", "width", "finite"),
    ("[[plotter]]\nvirtual = true\nwidth = 100\nheight = nan\n", "height", "finite"),
    ("[[plotter]]\nvirtual = true\nwidth = -inf\nheight = 100\n", "width", "finite"),
    ("[[plotter]]\ndevice = '/dev/a'\nbaud = 0\n", "baud", "from 300"),
    ("[[plotter]]\ndevice = '/dev/a'\nbaud = 1e9\n", "baud", "an integer"),
])  # fmt: skip
def test_plotters_file_numbers_and_boards_name_file_line_and_key(tmp_path, text, key, message):
    """A shell string, inf or nan is refused naming the file, the line and the key; no
    board name that is not a profile reaches make."""
    marker = tmp_path / "ran"
    path = tmp_path / "plotters.toml"
    path.write_text("# two plotters\n[[plotter]]\nvirtual = true\n\n"
                    + text.format(shell=SHELL.format(marker=marker)))
    line = next(n for n, row in enumerate(path.read_text().splitlines(), 1)
                if row.startswith(key))
    with pytest.raises(ConfigError) as info:
        read_plotters_file(path)
    assert str(info.value).startswith(f"{path}:{line}: plotter 2: {key}: "), info.value
    assert message in str(info.value)
    assert not marker.exists()


def test_command_line_board_and_numbers_are_checked_before_anything_runs(tmp_path, capsys):
    marker = tmp_path / "ran"
    for argv in (["--board", SHELL.format(marker=marker)], ["--max-upload-mb", "inf"],
                 ["--sim-speed", "nan"], ["--import-time-limit", "-1"], ["--port", "0"]):
        with pytest.raises(SystemExit):
            serve_args(*argv)
        assert argv[0] in capsys.readouterr().err
    assert not marker.exists()


def test_a_virtual_plotter_refuses_an_unknown_board_before_make(tmp_path):
    from plotbridge.profiles import UnknownBoard, board_profiles
    from plotbridge.virtual import VirtualPlotter

    assert "uno-cnc-shield" in board_profiles() and "mega-ramps14" in board_profiles()
    with pytest.raises(UnknownBoard, match="one of mega-l298n"):
        VirtualPlotter(tmp_path, board=SHELL.format(marker=tmp_path / "ran"))
    assert not (tmp_path / "ran").exists()
