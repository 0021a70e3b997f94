"""Mission.render draws aia render's frame."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import aia

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))
DEFAULT = str(SOURCE / "scenarios" / "default.yaml")


def test_a_frame_is_aia_renders_first_frame(tmp_path):
    image = pytest.importorskip("matplotlib.image")
    r = subprocess.run([BINARY, "render", DEFAULT, "--seed", "3",
                        "--max-steps", "1", "--width", "320", "--height",
                        "240", "--out", str(tmp_path / "v.mp4"), "--frames",
                        str(tmp_path / "f"), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    want = image.imread(str(tmp_path / "f" / "frame_000000.png"))[:, :, :3]
    want = (want * 255).round().astype(np.uint8)
    m = aia.Mission(DEFAULT, seed=3)
    got = m.render(320, 240)
    assert got.shape == (240, 320, 3) and got.dtype == np.uint8
    # The same picture below the heads-up line (which names the policy:
    # "python" here).
    assert (got[16:] == want[16:]).all()
    assert (got[:16] != want[:16]).any()


def test_frames_follow_the_mission():
    m = aia.Mission(DEFAULT, seed=3, overrides={"robots.count": 3,
                                                "targets.count": 2})
    first = m.render(160, 120)
    greedy = aia.builtin_policy("greedy")
    for _ in range(3):
        m.step(greedy.decide(m))
    assert (m.render(160, 120) != first).any()
    assert m.render(200, 100).shape == (100, 200, 3)
    with pytest.raises(aia.InputError, match=r"aia.Mission.render: width: "
                       r"must be an integer in \[16, 8192\]"):
        m.render(8, 8)
