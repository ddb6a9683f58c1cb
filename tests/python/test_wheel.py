"""scripts/build-wheel.sh makes a wheel that installs where it was not built: installed into a
fresh virtual environment, every native library its module needs outside the C runtime
resolves inside the wheel (mvpt.libs/), with no library path set, and it renders."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# The C and C++ runtimes, which a manylinux wheel takes from the system.
SYSTEM = ("libc.so", "libm.so", "libstdc++.so", "libgcc_s.so", "libpthread.so", "libdl.so", "librt.so",
          "ld-linux", "linux-vdso", "libz.so")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    if not (ROOT / ".venv" / "bin" / "python").exists():
        pytest.skip("needs the repository's .venv (scripts/setup.sh) to build the wheel")
    if shutil.which("ldd") is None:
        pytest.skip("needs ldd to list the module's libraries")
    out = tmp_path_factory.mktemp("dist")
    proc = subprocess.run(["bash", str(ROOT / "scripts" / "build-wheel.sh"), str(out)], capture_output=True,
                          text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return Path(proc.stdout.strip().splitlines()[-1])


def test_wheel_is_self_contained(wheel, tmp_path):
    assert "manylinux" in wheel.name, wheel.name
    env_dir = tmp_path / "env"
    venv.create(env_dir, with_pip=True)
    py = env_dir / "bin" / "python"
    clean = {k: v for k, v in os.environ.items() if k not in ("LD_LIBRARY_PATH", "PYTHONPATH")}
    # numpy from the package index (or pip's cache); mvpt from the wheel alone.
    subprocess.run([py, "-m", "pip", "install", "-q", "numpy"], check=True, env=clean)
    subprocess.run([py, "-m", "pip", "install", "-q", "--no-deps", str(wheel)], check=True, env=clean)
    site = Path(subprocess.run([py, "-c", "import sysconfig; print(sysconfig.get_paths()['platlib'])"],
                               capture_output=True, text=True, check=True, env=clean).stdout.strip())
    (core,) = (site / "mvpt").glob("_core*.so")
    ldd = subprocess.run(["ldd", str(core)], capture_output=True, text=True, check=True, env=clean).stdout
    assert "not found" not in ldd, ldd
    bundled = []
    for line in ldd.splitlines():
        name = line.split()[0]
        if any(s in name for s in SYSTEM):
            continue
        path = line.split("=>")[1].split()[0]
        assert Path(path).resolve().parent == (site / "mvpt.libs").resolve(), line
        bundled.append(name)
    assert any("embree" in n for n in bundled) and any("tbb" in n for n in bundled), bundled
    code = ("import mvpt; s = mvpt.load_string(open(mvpt.__path__[0] + '/data/demo.xml').read(), res=8); "
            "r = mvpt.render(s, spp=1, method='mvpt', views=[0, 1]); print(r.stats['samples'])")
    run = subprocess.run([py, "-c", code], capture_output=True, text=True, env=clean, cwd=tmp_path)
    assert run.returncode == 0 and int(run.stdout.strip()) > 0, run.stderr
    assert str(site) in subprocess.run([py, "-c", "import mvpt; print(mvpt.__file__)"], capture_output=True,
                                       text=True, env=clean, cwd=tmp_path).stdout


def test_ray_ships_the_wheel(wheel, tmp_path):
    """distributed.render(wheel=...): Ray installs the wheel for the tasks (its py_modules), which
    then run the wheel's mvpt, not this environment's."""
    ray = pytest.importorskip("ray", reason='Ray is an optional dependency: pip install "mvpt[ray]"')
    from mvpt import distributed
    assert not ray.is_initialized()
    scene = tmp_path / "demo.xml"
    scene.write_text((ROOT / "python" / "mvpt" / "data" / "demo.xml").read_text())
    r = distributed.render(scene, spp=8, method="mvpt", views=[0, 1], defines={"res": 8}, workers=1, wheel=wheel)
    (module,) = r.stats["distributed"]["worker_modules"]
    assert "runtime_resources" in module and wheel.stem in module, module
    assert r.stats["samples"] > 0 and r.stats["passes"] == 8
