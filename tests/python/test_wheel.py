"""`pip install .` into a virtualenv (setup.py driving CMake, offline): the
package there loads its own plugin and model, and its `aia` command runs,
while this build tree and the source's models/ are there too."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("AIA_SOURCE_DIR", Path(__file__).parents[2]))
BINARY = os.environ.get("AIA_BINARY", str(SOURCE / "build" / "aia"))


def test_pip_install_into_a_virtualenv(tmp_path):
    pytest.importorskip("wheel")  # Debian's python3-wheel: no download
    venv = tmp_path / "venv"
    r = subprocess.run([sys.executable, "-m", "venv",
                        "--system-site-packages", str(venv)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)  # not the build tree's package
    # This build's folder (already built: the wheel takes its files).
    env["AIA_BUILD_DIR"] = str(Path(BINARY).parent)
    r = subprocess.run([str(venv / "bin" / "pip"), "install", "-q",
                        "--no-build-isolation", "--no-deps", "--no-index",
                        str(SOURCE)], capture_output=True, text=True, env=env,
                       timeout=600)
    assert r.returncode == 0, r.stdout + r.stderr
    site = next((venv / "lib").glob("python3*/site-packages"))
    check = f"""
import os, aia
from aia import _aia
pkg = os.path.realpath({str(site / "aia")!r})
assert os.path.realpath(aia.__file__).startswith(pkg), aia.__file__
assert _aia._default_model_path().startswith(pkg + "/share/aia/models/")
assert _aia._default_model_path("none") == \
    pkg + "/share/aia/models/igbnet_learned.pt", _aia._default_model_path("none")
m = aia.Mission({str(SOURCE / "scenarios" / "default.yaml")!r},
                overrides={{"robots.count": 2, "targets.count": 1}})
m.step(aia.builtin_policy("igbnet").decide(m))
maps = [l.split()[-1] for l in open("/proc/self/maps") if "libaia_torch" in l]
assert maps and all(os.path.realpath(p) == pkg + "/lib/aia/libaia_torch.so"
                    for p in maps), maps
print("ok")
"""
    # From the source tree, whose models/igbnet.pt must not be taken.
    r = subprocess.run([str(venv / "bin" / "python"), "-c", check],
                       cwd=SOURCE, capture_output=True, text=True, env=env)
    assert r.returncode == 0 and r.stdout == "ok\n", r.stdout + r.stderr
    out = tmp_path / "run"
    r = subprocess.run([str(venv / "bin" / "aia"), "run",
                        "scenarios/default.yaml", "--policy", "igbnet",
                        "--max-steps", "2", "--out", str(out), "--quiet"],
                       cwd=SOURCE, capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stderr
    assert f"  model: {os.path.realpath(site)}/aia/share/aia/models/" \
        "igbnet.pt\n" in (out / "effective.yaml").read_text()
