"""Quiet runs: without a display the figures are drawn off screen with no X warning.

``pilegroup.offscreen`` names VTK's off-screen window (EGL, else OSMesa) when there is no
display; a run that renders its mesh views prints nothing about an X server.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from pilegroup import offscreen

BIN = Path(sys.executable).parent


@pytest.mark.parametrize("env", [{"DISPLAY": ":0"}, {"WAYLAND_DISPLAY": "wayland-0"},
                                 {offscreen.VARIABLE: "vtkXOpenGLRenderWindow"}])
def test_a_display_or_the_user_s_choice_is_left_alone(env):
    before = dict(env)
    assert offscreen.choose_offscreen_window(env) is None
    assert env == before


def test_without_a_display_the_first_window_whose_library_loads(monkeypatch):
    if not sys.platform.startswith("linux"):
        pytest.skip("VTK chooses its window at run time on Linux")
    loads = {"libOSMesa.so.8"}
    monkeypatch.setattr(offscreen, "_loads", lambda names: bool(loads & set(names)))
    env: dict[str, str] = {}
    assert offscreen.choose_offscreen_window(env) == "vtkOSOpenGLRenderWindow"
    assert env == {offscreen.VARIABLE: "vtkOSOpenGLRenderWindow"}
    loads.add("libEGL.so.1")
    env = {}
    assert offscreen.choose_offscreen_window(env) == "vtkEGLRenderWindow"
    loads.clear()
    env = {}
    assert offscreen.choose_offscreen_window(env) is None and env == {}


def test_a_mesh_run_prints_no_x_server_warning(tmp_path):
    env = {k: v for k, v in os.environ.items()
           if k not in ("DISPLAY", "WAYLAND_DISPLAY", offscreen.VARIABLE)}
    env["PILEGROUP_MESH_CACHE"] = str(tmp_path / "cache")
    out = tmp_path / "run"
    r = subprocess.run([str(BIN / "pilegroup"), "run", "single_pile", "--stop-after", "mesh",
                        "--out", str(out)], capture_output=True, text=True, timeout=900, env=env)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "X server" not in r.stderr and "vtkXOpenGLRenderWindow" not in r.stderr, r.stderr
    for name in ("plan.png", "cutaway.png"):
        assert (out / "mesh" / name).stat().st_size > 10_000, name
