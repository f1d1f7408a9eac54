"""Output folders: party writes only where it may, replaces only what it wrote, one run at a time.

Every command that writes results (``party drape``, ``run``, ``validate``, ``batch``) holds its ``--out``
folder through :func:`open_output` for the whole run:

- ``--out`` must name a folder of its own: the current folder, a folder above it, the home
  folder and the file system's root are refused, and so is an existing file.
- A folder party writes into carries :data:`MARKER`, a small JSON file that says so. A folder
  that already exists is taken only when everything in it is party's own: the marker, and
  entries that a party command writes, known by name (:data:`OUTPUTS`). A folder holding
  anything else (a user's thesis, photos) is refused with one line naming what is there, unless
  ``overwrite`` is given; even then party replaces only entries it knows by name, never others.
- The marker is also the lock: the run holds an exclusive ``flock`` on it, so a second run into
  the same folder is refused with an error naming the first (command, process, start time).
  The kernel releases the lock when a process dies, even by ``kill -9``.
- Results that must appear all at once (a drape's) are written into a staging folder inside
  the output folder (:meth:`OutputFolder.staging`) and moved into place by
  :meth:`OutputFolder.publish`; a staging folder left by a killed run is removed when the next
  run takes the folder.
"""

from __future__ import annotations

import datetime
import fnmatch
import json
import os
import shutil
from pathlib import Path
from typing import Iterable

from ..errors import InvalidInput

MARKER = ".party"
"""The file that marks a folder as party's output, and that a running command holds locked."""

STAGING_PREFIX = ".party-staging-"
"""Name prefix of the staging folders inside an output folder (:meth:`OutputFolder.staging`)."""

PARTIAL = ("*.part", "*.part.npz")
"""Names of files an atomic write (:mod:`party.output.frames`) had not finished."""

OUTPUTS: dict[str, tuple[str, ...]] = {
    "drape": ("garment.obj", "garment.glb", "body.obj", "body_*.obj", "images", "relaxation.json",
              "summary.json", "checkpoint.npz"),
    "run": ("frames", "colliders", "images", "relaxation.json", "summary.json", "checkpoint.npz", "sewn.npz"),
    "validate": ("results.json", "*.png"),
    "batch": ("*__*__*", "manifest.parquet", "contact_sheet.png", "logs"),
}
"""Top-level entries (file-name patterns) each command writes into its output folder."""


def _known(name: str, patterns: Iterable[str]) -> bool:
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


def party_entry(name: str) -> bool:
    """Whether a top-level entry called ``name`` is one that some party command writes."""
    return (name == MARKER or name.startswith(STAGING_PREFIX) or _known(name, PARTIAL)
            or any(_known(name, patterns) for patterns in OUTPUTS.values()))


def check_output_path(path: Path) -> Path:
    """``path`` made absolute, or :class:`InvalidInput` where it cannot be an output folder of
    its own: empty, the current folder or one above it, the home folder or one above it (the
    root among them), or an existing file."""
    text = str(path)
    if text.strip() == "":
        raise InvalidInput("--out is empty; name a folder for the results, e.g. --out out/run1")
    resolved = Path(os.path.abspath(os.path.expanduser(text)))
    real = resolved.resolve()
    cwd = Path.cwd().resolve()
    home = Path.home().resolve()
    if real == cwd or real in cwd.parents:
        raise InvalidInput(f"--out {text}: that is the current folder or one above it; party writes its results "
                           "into a folder of their own, e.g. --out out/run1")
    if real == home or real in home.parents:
        raise InvalidInput(f"--out {text}: that is the home folder or one above it; name a folder of its own "
                           "for the results")
    if real.exists() and not real.is_dir():
        raise InvalidInput(f"--out {text} is a file, not a folder; name a folder for the results")
    return resolved


class OutputFolder:
    """An output folder held by one running command (see the module docstring); use as a
    context manager, or call :meth:`close`.

    Attributes:
        path: The folder (absolute).
        command: The command writing into it (a key of :data:`OUTPUTS`).
    """

    def __init__(self, path: Path, command: str, *, overwrite: bool = False, description: str = "") -> None:
        if command not in OUTPUTS:
            raise ValueError(f"unknown command {command!r}")
        self.command = command
        self.path = check_output_path(Path(path))
        self.shown = str(path)
        self._fd: int | None = None
        self._created = _first_missing(self.path)
        foreign = self._foreign_entries()
        if foreign and not overwrite:
            listed = ", ".join(foreign[:4]) + (f" and {len(foreign) - 4} more" if len(foreign) > 4 else "")
            raise InvalidInput(f"--out {self.shown} holds files party did not write ({listed}); choose another "
                               "folder, or pass --overwrite to write party's results beside them (only party's "
                               "own files are replaced)")
        self._lock(description)
        self._remove_stale_staging()

    def _foreign_entries(self) -> list[str]:
        """The entries of the folder that party cannot know as its own: all of them in a folder
        without the marker, else those no command writes."""
        if not self.path.exists():
            return []
        try:
            names = sorted(os.listdir(self.path))
        except OSError as error:
            raise InvalidInput(f"--out {self.shown}: cannot read the folder ({error.strerror})") from None
        if MARKER not in names:
            return [n + "/" if (self.path / n).is_dir() else n for n in names]
        return [n + "/" if (self.path / n).is_dir() else n for n in names if not party_entry(n)]

    def _lock(self, description: str) -> None:
        import fcntl

        try:
            self.path.mkdir(parents=True, exist_ok=True)
            fd = os.open(self.path / MARKER, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as error:
            raise InvalidInput(f"--out {self.shown}: cannot write there ({error.strerror})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            os.close(fd)
            raise InvalidInput(f"--out {self.shown} is in use by another party run ({holder}); wait for it to "
                               "finish or choose another folder") from None
        self._fd = fd
        record = {"party": _version(), "command": self.command, "run": description, "pid": os.getpid(),
                  "started": datetime.datetime.now().isoformat(timespec="seconds")}
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(record) + "\n").encode(), 0)
        except OSError as error:
            self.close()
            raise InvalidInput(f"--out {self.shown}: cannot write there ({error.strerror})") from None

    def _remove_stale_staging(self) -> None:
        """Staging folders and half-written files of runs that were killed (none can be running:
        this run holds the lock)."""
        for entry in self.path.iterdir():
            if entry.name.startswith(STAGING_PREFIX) and entry.is_dir():
                shutil.rmtree(entry, ignore_errors=True)
            elif _known(entry.name, PARTIAL) and entry.is_file():
                entry.unlink(missing_ok=True)

    def staging(self) -> Path:
        """A new, empty staging folder inside the output folder, for :meth:`publish`."""
        staging = self.path / f"{STAGING_PREFIX}{os.getpid()}"
        if staging.exists():
            shutil.rmtree(staging)
        staging.mkdir()
        return staging

    def publish(self, staging: Path, *, last: str = "summary.json") -> None:
        """Move every entry of ``staging`` into the folder, replacing entries of the same name
        (which are party's: the folder was checked when it was taken), and remove this command's
        entries that this run did not write again (a previous run's); ``last`` is removed first
        and moved in last, so that a folder holding it holds a whole result. ``staging`` is
        removed."""
        produced = {entry.name for entry in staging.iterdir()}
        (self.path / last).unlink(missing_ok=True)
        for entry in self.path.iterdir():
            if entry.name not in produced and _known(entry.name, OUTPUTS[self.command]):
                remove(entry)
        for name in sorted(produced, key=lambda n: n == last):
            target = self.path / name
            if target.exists() or target.is_symlink():
                remove(target)
            os.replace(staging / name, target)
        shutil.rmtree(staging, ignore_errors=True)

    def remove_own(self, name: str) -> None:
        """Remove the entry ``name``, one of this command's outputs, where it exists."""
        if not _known(name, OUTPUTS[self.command]):
            raise ValueError(f"{name!r} is not an output of party {self.command}")
        target = self.path / name
        if target.exists():
            remove(target)

    def close(self) -> None:
        """Release the folder (the marker stays, the lock goes). A folder this run made and
        left holding nothing but the marker (it stopped before writing anything: bad input
        found late) is removed again, with the folders made above it."""
        if self._fd is None:
            return
        if self._created is not None and os.listdir(self.path) == [MARKER]:
            (self.path / MARKER).unlink()
            folder = self.path
            while True:
                folder.rmdir()
                if folder == self._created:
                    break
                folder = folder.parent
        os.close(self._fd)  # closing the descriptor releases the flock
        self._fd = None

    def __enter__(self) -> "OutputFolder":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_output(path: Path, command: str, *, overwrite: bool = False, description: str = "") -> OutputFolder:
    """Take ``path`` as ``command``'s output folder (see :class:`OutputFolder`)."""
    return OutputFolder(path, command, overwrite=overwrite, description=description)


def remove(entry: Path) -> None:
    """Remove a file, link or folder tree."""
    if entry.is_dir() and not entry.is_symlink():
        shutil.rmtree(entry)
    else:
        entry.unlink(missing_ok=True)


def _first_missing(path: Path) -> Path | None:
    """The outermost folder of ``path`` (itself included) that does not exist yet, or None."""
    missing = None
    for folder in (path, *path.parents):
        if folder.exists():
            break
        missing = folder
    return missing


def _holder(fd: int) -> str:
    """Who holds the lock, as the marker records it."""
    try:
        record = json.loads(os.pread(fd, 4096, 0).decode() or "{}")
        what = f"party {record.get('command', '?')}" + (f" {record['run']}" if record.get("run") else "")
        return f"{what}, process {record.get('pid', '?')}, started {record.get('started', '?')}"
    except (OSError, ValueError):
        return "another process"


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("party")
    except PackageNotFoundError:
        return "unknown"
