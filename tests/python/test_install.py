"""`pip install --no-build-isolation .` into a fresh virtual environment: `import overtake`
then works without PYTHONPATH, from the environment's own site-packages."""
import os
import pathlib
import subprocess
import sys

import pytest

from conftest import SOURCE


def test_pip_install_puts_overtake_into_a_fresh_virtual_environment(binary, tmp_path):
    venv = tmp_path / "venv"
    # Debian's interpreter, with its numpy, setuptools and wheel seen from the environment
    # (--system-site-packages): nothing is downloaded.
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True,
                   timeout=300)
    python = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    # The build folder the tests' binary came from: brought up to date, not built again.
    env["OVERTAKE_BUILD_DIR"] = str(pathlib.Path(binary).resolve().parent)
    p = subprocess.run([str(python), "-m", "pip", "install", "--no-build-isolation", "--no-index",
                        "--no-deps", "--quiet", str(SOURCE)], env=env, capture_output=True,
                       text=True, timeout=900)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]

    code = ("import overtake, numpy\n"
            "print(overtake.__file__)\n"
            "env = overtake.VecEnv(2, seed=3)\n"
            "obs, info = env.reset()\n"
            "obs, reward, terminated, truncated, info = env.step(numpy.zeros(2, dtype=numpy.int64))\n"
            "print(obs.shape, obs.dtype, reward.shape)\n")
    run = subprocess.run([str(python), "-c", code], env=env, cwd=tmp_path, capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    where, shapes = run.stdout.splitlines()
    assert pathlib.Path(where).resolve().is_relative_to(venv.resolve()), where
    assert "site-packages" in where
    assert shapes == "(2, 31) float32 (2,)"


def test_the_install_refuses_a_build_folder_that_is_not_one(binary, tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    # A file where the build folder should be: the build stops, naming it, and makes no wheel.
    bogus = tmp_path / "not-a-folder"
    bogus.write_text("x")
    env["OVERTAKE_BUILD_DIR"] = str(bogus)
    p = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-build-isolation", "--no-index",
                        "--no-deps", "-w", str(tmp_path / "wheels"), str(SOURCE)], env=env,
                       capture_output=True, text=True, timeout=900)
    assert p.returncode != 0
    assert f"OVERTAKE_BUILD_DIR={bogus} is not a folder" in p.stdout + p.stderr, p.stderr[-3000:]
    assert not (tmp_path / "wheels").exists() or not list((tmp_path / "wheels").glob("*.whl"))
