"""Small file helpers shared by every layer.

:func:`proc_kib` reads one value of a Linux ``/proc`` file (memory of this process and of the
machine). Atomic writes, so that an interrupted run never leaves a half-written JSON, CSV, mesh or
picture behind: the file is written under a temporary name in the same folder and renamed. A
write that fails (a full disk, a read-only folder, a directory in the file's place) raises
:class:`~pilegroup.errors.OutputError` naming the file, not its temporary name.
"""

from __future__ import annotations

import dataclasses
import json
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from pilegroup.errors import OutputError


def proc_kib(path: str, key: str) -> float | None:
    """The value of the line ``key: N kB`` of a Linux ``/proc`` file, in KiB; ``None`` if none.

    E.g. ``proc_kib("/proc/self/status", "VmHWM")``; ``None`` where the file or line does not
    exist (not Linux).
    """
    try:
        with open(path, encoding="ascii") as fh:
            for line in fh:
                if line.startswith(f"{key}:"):
                    return float(line.split()[1])
    except OSError:
        pass
    return None


def json_default(obj: Any) -> Any:
    """``json.dumps(default=...)``: dataclasses, numpy scalars and arrays, paths, else ``str``."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return dataclasses.asdict(obj)
    if hasattr(obj, "tolist"):
        return obj.tolist()
    return str(obj)


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path to write ``path`` to; it replaces ``path`` when the block succeeds.

    The temporary file lies in the same folder (created if needed) and keeps the suffix of
    ``path``, so that writers that choose the format by the suffix (gmsh, pyvista) still do.
    If the block raises, the temporary file is removed and ``path`` is left as it was. The file
    gets the permissions of a file created with ``open`` (0666 less the umask), not ``mkstemp``'s
    private 0600. An ``OSError`` of the folder, the temporary file, the block or the rename is
    raised as :class:`~pilegroup.errors.OutputError` naming ``path``.
    """
    path = Path(path)
    try:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except FileExistsError:
            pass  # a file in the folder's place: mkstemp says "Not a directory"
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
        os.close(fd)
    except OSError as exc:
        raise OutputError(path, exc) from exc
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(path, exc) from exc
    finally:
        Path(tmp).unlink(missing_ok=True)


def _umask() -> int:
    """The process's umask (read by setting it and restoring it)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file and an atomic rename."""
    path = Path(path)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def write_json_atomic(path: str | Path, data: Any) -> Path:
    """Write ``data`` as indented JSON (dataclasses and numpy arrays allowed), atomically."""
    return write_text_atomic(path, json.dumps(data, indent=2, default=json_default) + "\n")


def read_json(path: str | Path) -> dict[str, Any] | None:
    """The JSON object in ``path``, or ``None`` when the file is missing, unreadable or not one."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None
