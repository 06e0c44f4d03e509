"""The OpenGL window VTK draws the PNG figures in when the machine has no display.

The figures (mesh views, the 3D view of a run) are drawn off screen. VTK's wheels choose their
OpenGL window at run time: X first, then EGL, then OSMesa, and each failed try prints a
warning. On a machine without an X display (a server, a batch node, a container) the X try
fails every time and prints ``vtkXOpenGLRenderWindow ... bad X server connection``, a warning
nobody can act on: the figures are then drawn with EGL all the same. Without a display this
module names the window VTK is to use (``VTK_DEFAULT_OPENGL_WINDOW``, read when a render window
is made): EGL if its library loads, else OSMesa if its library loads, else none (VTK's own
choice, whose warnings then say what to install). A display, or a window the user names
through ``VTK_DEFAULT_OPENGL_WINDOW``, is left alone (docs/results.md, "Figures and report of a
run").
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Mapping, MutableMapping

#: The environment variable VTK reads when it makes a render window.
VARIABLE = "VTK_DEFAULT_OPENGL_WINDOW"
#: VTK's off-screen windows in the order tried, each with the libraries that provide it.
WINDOWS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("vtkEGLRenderWindow", ("libEGL.so.1", "libEGL.so")),
    ("vtkOSOpenGLRenderWindow", ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")),
)


def _loads(names: tuple[str, ...]) -> bool:
    """Whether any of the shared libraries ``names`` loads."""
    for name in names:
        try:
            ctypes.CDLL(name)
        except OSError:
            continue
        return True
    return False


def has_display(environ: Mapping[str, str]) -> bool:
    """Whether ``environ`` names an X or Wayland display (or the platform is not Linux)."""
    return not sys.platform.startswith("linux") or bool(
        environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def choose_offscreen_window(environ: MutableMapping[str, str] = os.environ) -> str | None:
    """Name VTK's off-screen window in ``environ`` when there is no display; return it.

    ``None``: a display exists, the variable is already set, or neither EGL nor OSMesa loads.
    """
    if has_display(environ) or environ.get(VARIABLE):
        return None
    for window, libraries in WINDOWS:
        if _loads(libraries):
            environ[VARIABLE] = window
            return window
    return None
