"""The examples of examples/python run and print what docs/python.md says."""

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

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


def epoch_losses(out):
    return [float(l.split("train loss ")[1].split(",")[0])
            for l in out.splitlines() if l.startswith("epoch ")]


def test_train_igbnet_on_two_processes(tmp_path):
    """torch.distributed (gloo): each rank its own shard file, the global
    batch split between them; the ranks end with the same weights, and the
    training is one process's within tolerance (batch norm's statistics
    are each rank's own, so not exactly)."""
    binary = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
    for k in range(2):
        r = subprocess.run([binary, "dataset", "--episodes", "16", "--size",
                            "3x3", "--keep", "4", "--shard", f"{k}/2",
                            "--out", str(tmp_path / "d"), "--quiet"],
                           capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
    common = [str(tmp_path / "d"), "--epochs", "3", "--width", "4",
              "--hidden", "8", "--threads", "2"]
    two = run("train_igbnet.py", *common, str(tmp_path / "two.pt"),
              "--processes", "2")
    one = run("train_igbnet.py", *common, str(tmp_path / "one.pt"))
    assert "2 processes (gloo backend) by shard files" in two, two
    per_rank = ast.literal_eval(two.split("training samples per rank ")[1].split("]")[0]
                    + "]")
    total = ast.literal_eval(one.split("training samples per rank ")[1].split("]")[0]
                 + "]")
    assert len(per_rank) == 2 and min(per_rank) > 0
    assert sum(per_rank) == sum(total)
    assert "ranks agree on the weights: True" in two
    a, b = epoch_losses(two), epoch_losses(one)
    assert len(a) == len(b) == 3
    assert all(abs(x - y) < 0.05 for x, y in zip(a, b)), (a, b)
    assert (tmp_path / "two.pt").exists()


def test_train_rl_quick(tmp_path):
    """The PPO example's smoke run writes a model aia run accepts."""
    model = tmp_path / "rl.pt"
    out = run("train_rl.py", "--quick", "--out", str(model))
    assert "update 2 " in out and "test (2 missions" in out, out
    binary = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
    r = subprocess.run([binary, "run", str(SOURCE / "scenarios" /
                                           "default.yaml"),
                        "--set", f"policy.model={model}",
                        "--set", "policy.coordination=none",
                        "--max-steps", "3", "--out", str(tmp_path / "run"),
                        "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert str(model) in (tmp_path / "run" / "effective.yaml").read_text()


def test_train_rl_fine_tunes_the_heads_alone(tmp_path):
    """--freeze-trunk: PPO changes the MLP and leaves the convolutions as
    --init had them; without --init it is refused."""
    torch = pytest.importorskip("torch")
    from aia import network
    init = SOURCE / "models" / "igbnet_learned.pt"
    model = tmp_path / "heads.pt"
    out = run("train_rl.py", "--quick", "--freeze-trunk", "--init",
              str(init), "--lr", "1e-2", "--out", str(model))
    assert "update 2 " in out, out
    before, _ = network.load_model(init)
    after, meta = network.load_model(model)
    assert meta["trail"] and meta["reach_world"]  # --init's network
    b, a = before.state_dict(), after.state_dict()
    for name in b:
        if name.startswith(("fc1.", "fc2.")):
            continue
        assert torch.equal(a[name], b[name]), name
    assert not torch.equal(a["fc2.weight"], b["fc2.weight"])
    r = subprocess.run([sys.executable, str(SOURCE / "examples" / "python" /
                                            "train_rl.py"), "--quick",
                        "--freeze-trunk", "--out", str(tmp_path / "x.pt")],
                       cwd=SOURCE, capture_output=True, text=True, timeout=60)
    assert r.returncode != 0 and "--freeze-trunk: needs --init" in r.stderr


def test_video(tmp_path):
    out = run("video.py", str(tmp_path / "v.mp4"))
    assert "success True" in out
    probe = subprocess.run(["ffprobe", "-v", "error", "-count_frames",
                            "-show_entries", "stream=nb_read_frames,codec_name",
                            "-of", "csv=p=0", str(tmp_path / "v.mp4")],
                           capture_output=True, text=True)
    codec, frames = probe.stdout.strip().split(",")
    assert codec == "h264" and int(frames) == int(out.split()[2])
