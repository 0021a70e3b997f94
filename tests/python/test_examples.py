"""The examples of examples/python run and print what docs/python.md says."""

import os
import subprocess
import sys
from pathlib import Path

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))


def run(name, *args):
    r = subprocess.run([sys.executable, str(SOURCE / "examples" / "python" /
                                            name), *args],
                       cwd=SOURCE, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_random_policy():
    out = run("random_policy.py")
    assert "random moves: success" in out and "greedy: success True" in out


def test_parallel_env_loop():
    assert "success True" in run("parallel_env_loop.py")


def test_heuristic_scored_beside_the_builtins(tmp_path):
    binary = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
    r = subprocess.run([binary, "eval", "--sizes", "3x3", "--seeds", "3",
                        "--policies", "greedy", "--out", str(tmp_path),
                        "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out = run("heuristic_eval.py", str(tmp_path), "3x3", "3")
    lines = [l.split()[0] for l in out.splitlines()[-2:]]
    assert lines == ["nearest_target", "greedy"], out


def test_train_igbnet(tmp_path):
    binary = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
    r = subprocess.run([binary, "dataset", "--episodes", "6", "--size", "3x3",
                        "--keep", "4", "--out", str(tmp_path / "d"),
                        "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    out = run("train_igbnet.py", str(tmp_path / "d"), str(tmp_path / "m.pt"),
              "--epochs", "1", "--width", "4", "--hidden", "8")
    assert "epoch 1: train loss" in out and (tmp_path / "m.pt").exists()


def test_video(tmp_path):
    out = run("video.py", str(tmp_path / "v.mp4"))
    assert "success True" in out
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames",
                            "-show_entries", "stream=nb_read_frames,codec_name",
                            "-of", "csv=p=0", str(tmp_path / "v.mp4")],
                           capture_output=True, text=True)
    codec, frames = probe.stdout.strip().split(",")
    assert codec == "h264" and int(frames) == int(out.split()[2])
