"""The plotting tools under tools/ on bad input: one `error:` line and exit
code 2 (they gave tracebacks), and figures written whole or not at all."""

import os
import subprocess
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
PYTHON = "/usr/bin/python3"

pytest.importorskip("matplotlib")


def tool(name, *args):
    return subprocess.run([PYTHON, str(SOURCE / "tools" / name), *args],
                          capture_output=True, text=True)


def refused(result, *parts):
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith("error: "), result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    for p in parts:
        assert p in result.stderr, (p, result.stderr)


def write(path, text, mode="w"):
    with open(path, mode) as f:
        f.write(text)
    return str(path)


def test_bad_tables_are_one_error_line(tmp_path):
    summary = "size,policy,instances,success_rate,flowtime_increase\n"
    cases = [
        ("plot_eval.py", write(tmp_path / "word.csv", summary + "3x3,g,2,abc,1\n"),
         "word.csv:2: success_rate: must be a finite number, got 'abc'"),
        ("plot_eval.py", write(tmp_path / "nan.csv", summary + "3x3,g,2,0.5,nan\n"),
         "nan.csv:2: flowtime_increase: must be a finite number"),
        ("plot_eval.py", write(tmp_path / "bytes.csv", b"\xff\xfe\x00",
                               "wb"),
         "not UTF-8 text"),
        ("plot_eval.py", write(tmp_path / "runs.csv", "size,policy\n3x3,g\n"),
         "no column instances, success_rate, flowtime_increase"),
        ("plot_training.py", write(tmp_path / "log.csv", "epoch,train_loss\n1,2\n"),
         "no column train_acc"),
        ("plot_training.py", str(tmp_path / "missing.csv"), "no such file"),
        ("plot_trace.py", write(tmp_path / "trace.csv",
                                "step,target,min_det\n0,-1,1\n"),
         "trace.csv:2: target: must be a whole number >= 0, got '-1'"),
        ("plot_trace.py", str(tmp_path), "Is a directory"),
    ]
    for name, path, part in cases:
        refused(tool(name, path, "--out", str(tmp_path / "out.png")), part)
    assert not (tmp_path / "out.png").exists()


def test_figures_go_where_asked_and_never_over_an_input(tmp_path):
    run = tmp_path / "run"
    r = subprocess.run([BINARY, "run", str(SOURCE / "scenarios/default.yaml"),
                        "--policy", "greedy", "--max-steps", "3", "--out",
                        str(run), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    trace = str(run / "trace.csv")
    # An output without an extension is a PNG (the temporary file's name
    # was taken for a format); a missing folder is made.
    assert tool("plot_trace.py", trace, "--out",
                str(tmp_path / "new" / "plot")).returncode == 0
    with open(tmp_path / "new" / "plot", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert os.listdir(tmp_path / "new") == ["plot"]  # no temporary left
    refused(tool("plot_trace.py", trace, "--out", str(tmp_path)),
            "is a folder")
    refused(tool("plot_trace.py", trace, "--out", trace), "is an input")
    refused(tool("plot_training.py", str(SOURCE / "models/igbnet.train.csv"),
                 "--out", str(tmp_path / "x.csv")), "writes no .csv files")


def test_a_closed_pipe_ends_a_tool_without_a_traceback():
    # A tool whose reader has gone (`tool | head`): exit 141, nothing on
    # stderr, as a shell command ends.
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import tool_io\n"
            "def main():\n"
            "    raise BrokenPipeError(32, 'Broken pipe')\n"
            "tool_io.run(main)\n")
    r = subprocess.run([PYTHON, "-c", code, str(SOURCE / "tools")],
                       capture_output=True, text=True)
    assert r.returncode == 141, r.stderr
    assert r.stderr == ""
