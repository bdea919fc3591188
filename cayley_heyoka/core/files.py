"""Our files on disk: where they may be written, how they are written, how they are checked.

Every file the commands write (result, reference, sweep and check files, plots) follows one
policy (docs/scenes.md, "Files"):

* **Destination checked first.** Before any work, :func:`check_destination` refuses a missing
  or read-only directory, a directory given as the file, and an existing file that is not one
  of ours of the same kind (unless ``overwrite``). A result file of ours is replaced: running
  the same command again is the usual way to redo a run, and the old file survives until the
  new one is complete.
* **Atomic.** :func:`write_atomically` writes ``.NAME.tmp-PID`` beside the file, flushes it to
  disk and renames it over the file: a process killed at any moment leaves the previous file
  or the new one, never a mixture. A failed write (a full disk) removes its temporary; one
  left by a killed process is removed by the next write to the same name.
* **Checksummed.** HDF5 files carry the SHA-256 of their contents (every attribute and every
  dataset, in a fixed order) in the root attribute ``sha256``; :func:`open_ours` verifies it,
  so a damaged file is refused instead of read as NaNs. Files of format version 1 (before the
  checksum) are still read, unchecked.
"""

from __future__ import annotations

import contextlib
import errno
import glob
import hashlib
import json
import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

#: Version of the layout of result, sweep and check files; version 2 added the checksum,
#: version 3 the netCDF-4 layout of results and sweeps (named dimensions: any netCDF reader,
#: xarray among them, opens the file). Older versions are still read.
FORMAT_VERSION = 3
#: HDF5's dimension-scale bookkeeping: object references, i.e. addresses in the file. The
#: checksum takes the attachments by name instead (:func:`digest`).
_SCALE_ATTRIBUTES = frozenset({"DIMENSION_LIST", "REFERENCE_LIST"})
#: The ``format`` attribute of each kind of HDF5 file we write.
FORMATS = {
    "result": "cayley_heyoka.result",
    "sweep": "cayley_heyoka.sweep",
    "check": "cayley_heyoka.check",
}
#: Root attribute holding the checksum.
DIGEST = "sha256"
#: What a figure we write says it is (PNG text chunk ``Software``).
PNG_SOFTWARE = "cayley_heyoka"
_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


class ResultFileError(ValueError):
    """A file that cannot be read as one of ours: missing, not HDF5, damaged, incomplete.

    Parameters
    ----------
    path
        The file.
    what
        What is wrong with it.
    """

    def __init__(self, path: str | Path, what: str) -> None:
        self.path = Path(path)
        self.what = what
        super().__init__(f"{path}: {what}")


class OutputError(ValueError):
    """A file that may not or could not be written; nothing was changed at ``path``.

    Parameters
    ----------
    path
        The destination.
    what
        Why it was refused, or what failed.
    """

    def __init__(self, path: str | Path, what: str) -> None:
        self.path = Path(path)
        self.what = what
        super().__init__(f"{path}: {what}")

    @classmethod
    def failed_write(cls, path: str | Path, exc: OSError) -> OutputError:
        """A write to ``path`` that failed with ``exc`` and left the previous file as it was."""
        return WriteFailed(path, f"could not be written ({exc.strerror or exc}); nothing changed")


class WriteFailed(OutputError):
    """An :class:`OutputError` raised by the write itself (a full disk, a vanished directory),
    after the work it was to save: a command reports it as a stop (exit 1), not a refusal."""


# ---------------------------------------------------------------------- destinations
def check_destination(path: str | Path, kind: str, *, overwrite: bool = False) -> None:
    """Refuse, before any work, a destination that cannot or may not be written.

    Parameters
    ----------
    path
        Where the file is to go. A symbolic link is followed: its target is what is written.
    kind
        ``"result"``, ``"sweep"``, ``"check"`` or ``"plot"``: an existing file of ours of this
        kind may be replaced.
    overwrite
        Replace any existing regular file.

    Raises
    ------
    OutputError
        Naming the path and the rule: the directory is missing, not a directory or not
        writable; the path is a directory or a special file; or an existing file is not ours
        of this kind and ``overwrite`` is not set.
    """
    given = Path(path)
    try:
        _check_destination(given, kind, overwrite)
    except OSError as exc:  # a name too long, a loop of links, ...
        raise OutputError(given, f"cannot be written ({_reason(exc)})") from exc


def _check_destination(given: Path, kind: str, overwrite: bool) -> None:
    if given.is_symlink():
        try:
            os.stat(given)
        except OSError as exc:  # realpath would quietly cut a loop and write over the link
            if exc.errno == errno.ELOOP:
                raise OutputError(given, "is a loop of symbolic links") from None
    target = Path(os.path.realpath(given))
    parent = target.parent
    # The temporary's name is the longest this write needs.
    longest = len(os.fsencode(f".{target.name}.tmp-{os.getpid()}"))
    if longest > os.pathconf(parent if parent.is_dir() else "/", "PC_NAME_MAX"):
        raise OutputError(given, f"the file name is too long ({len(target.name)} characters)")
    if not parent.exists():
        raise OutputError(given, f"directory {parent} does not exist")
    if not parent.is_dir():
        raise OutputError(given, f"{parent} is not a directory")
    # The temporary goes beside the file, so the directory itself must take new files.
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(given, f"directory {parent} is not writable")
    if target.is_dir():
        raise OutputError(given, "is a directory; give a file name")
    if not target.exists():
        return
    if not target.is_file():
        raise OutputError(given, "exists and is not a regular file")
    if overwrite:
        return
    found = identify(target)
    if found != kind:
        what = f"a {found} file of ours" if found else "a file that is not one of ours"
        raise OutputError(
            given,
            f"exists and is {what}, not a {kind} file; refusing to replace it "
            "(choose another name, or pass --overwrite)",
        )


def identify(path: str | Path) -> str | None:
    """Which kind of our files ``path`` is (``"result"``, ... ``"plot"``), or None."""
    path = Path(path)
    if not path.is_file():  # opening a FIFO would wait for a writer; a device may never end
        return None
    try:
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError:
        return None
    if head == _PNG_MAGIC:
        return "plot" if _png_software(path).startswith(PNG_SOFTWARE) else None
    if not head.startswith(b"\x89HDF"):
        return None
    import h5py

    try:
        with h5py.File(path, "r") as f:
            fmt = f.attrs.get("format")
            legacy_check = "rows" in f and "passed" in f.attrs and "title" in f.attrs
    except Exception:  # noqa: BLE001 -- a damaged HDF5 file is simply not recognised
        return None
    for kind, name in FORMATS.items():
        if fmt == name:
            return kind
    # Check files of format version 1 had no format attribute.
    return "check" if fmt is None and legacy_check else None


def _png_software(path: Path) -> str:
    """The ``Software`` text chunk of a PNG file ('' if none before the image data)."""
    with open(path, "rb") as f:
        f.seek(len(_PNG_MAGIC))
        while True:
            header = f.read(8)
            if len(header) < 8:
                return ""
            size, tag = int.from_bytes(header[:4], "big"), header[4:]
            if tag == b"IDAT" or size > 1 << 20:
                return ""
            body = f.read(size + 4)[:size]
            if tag == b"tEXt" and body.startswith(b"Software\0"):
                return body[len(b"Software\0") :].decode("latin-1")


# ---------------------------------------------------------------------- writing
class Staged:
    """A file being written under a temporary name beside its destination.

    ``tmp`` is ``.NAME.tmp-PID`` in the destination's directory (symbolic links resolved);
    :meth:`commit` flushes it and renames it over the destination, :meth:`discard` removes it.
    Temporaries of the same name left by processes that no longer run are removed on creation.
    """

    def __init__(self, path: str | Path) -> None:
        from .signals import begin_work

        begin_work()  # a temporary is about to exist: a signal no longer ends the process at once
        self.path = Path(path)
        self.target = Path(os.path.realpath(self.path))
        self.tmp = self.target.with_name(f".{self.target.name}.tmp-{os.getpid()}")
        _remove_stale(self.target)

    def commit(self) -> None:
        """Put the temporary in place of the destination, durably."""
        try:
            with open(self.tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(self.tmp, self.target)
            _fsync_directory(self.target.parent)
        except OSError as exc:
            self.discard()
            raise OutputError.failed_write(self.path, exc) from exc

    def discard(self) -> None:
        """Remove the temporary (the destination is untouched)."""
        with contextlib.suppress(FileNotFoundError):
            self.tmp.unlink()


def write_atomically(path: str | Path, fill: Callable[[Path], None]) -> None:
    """Write a file by ``fill(temporary_path)`` and rename it into place.

    Raises
    ------
    OutputError
        When writing fails (a full disk, a vanished directory): the temporary is removed and
        the file at ``path``, if any, is as it was.
    """
    staged = Staged(path)
    try:
        fill(staged.tmp)
    except OSError as exc:
        staged.discard()
        raise OutputError.failed_write(path, exc) from exc
    except BaseException:
        staged.discard()
        raise
    staged.commit()


def write_hdf5(path: str | Path, fill: Callable[[Any], None]) -> None:
    """Write an HDF5 file atomically: ``fill(h5py_file)``, then its checksum."""
    import h5py

    def write(tmp: Path) -> None:
        # Creation order kept, as netCDF-4 keeps it: readers list variables as written.
        with h5py.File(tmp, "w", track_order=True) as f:
            fill(f)
            seal(f)

    write_atomically(path, write)


def seal(f: Any) -> None:
    """Store the checksum of an open HDF5 file's contents (the last thing written)."""
    f.attrs[DIGEST] = digest(f)


def _remove_stale(target: Path) -> None:
    prefix = f".{target.name}.tmp-"
    with contextlib.suppress(OSError):
        for tmp in target.parent.glob(f"{glob.escape(prefix)}*"):
            pid = tmp.name[len(prefix) :]
            if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
                tmp.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return True


def _fsync_directory(directory: Path) -> None:
    # Makes the rename itself durable; some file systems cannot open a directory for this.
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _reason(exc: OSError) -> str:
    return exc.strerror or str(exc)


# ---------------------------------------------------------------------- reading
@contextlib.contextmanager
def open_ours(path: str | Path, kind: str) -> Iterator[Any]:
    """Open one of our HDF5 files for reading, its format and checksum verified.

    Anything that goes wrong while the file is read inside the ``with`` block (a missing
    dataset, metadata that is not JSON, unreadable data) is raised as :class:`ResultFileError`
    naming the file.

    Raises
    ------
    ResultFileError
        The file is missing, not HDF5 (empty, text, truncated), not our ``kind`` of file, of a
        newer format version, or damaged (its checksum differs).
    """
    import h5py

    path = Path(path)
    if not path.exists():
        raise ResultFileError(path, "no such file")
    if path.is_dir():
        raise ResultFileError(path, "is a directory, not a file")
    if not path.is_file():
        raise ResultFileError(path, "is not a regular file (a pipe, socket or device)")
    try:
        f = h5py.File(path, "r")
    except (OSError, RuntimeError, ValueError) as exc:
        size = path.stat().st_size
        what = "empty file" if size == 0 else f"not an HDF5 file, or a truncated one ({size} bytes)"
        raise ResultFileError(path, what) from exc
    with f:
        try:
            _verify(f, kind)
            yield f
        except ResultFileError as exc:
            if exc.path != path:
                raise ResultFileError(path, exc.what) from exc
            raise
        except (
            KeyError,
            ValueError,
            TypeError,
            OSError,
            IndexError,
            RuntimeError,
            AttributeError,
        ) as exc:
            # HDF5 reports damaged structures as any of these (RuntimeError: a bad B-tree).
            raise ResultFileError(path, f"damaged or incomplete {kind} file: {exc}") from exc


def _verify(f: Any, kind: str) -> None:
    path = Path(f.filename)
    fmt = f.attrs.get("format")
    if kind == "check" and fmt is None and "rows" in f and "passed" in f.attrs:
        return  # a check file of format version 1: no marker and no checksum
    if fmt != FORMATS[kind]:
        found = next((k for k, v in FORMATS.items() if v == fmt), None)
        if found:
            what = f"a {found} file"
        elif fmt is None:
            what = "an HDF5 file without a format attribute (not written by cayley_heyoka)"
        else:
            what = f"an HDF5 file of format {fmt!r}"
        raise ResultFileError(path, f"{what}, not a {kind} file")
    version = f.attrs.get("format_version")
    if not isinstance(version, int | np.integer) or version < 1:
        raise ResultFileError(path, f"bad format_version {version!r}")
    if version > FORMAT_VERSION:
        raise ResultFileError(
            path,
            f"format version {int(version)} is newer than this library reads "
            f"({FORMAT_VERSION}); upgrade cayley_heyoka",
        )
    if version >= 2:
        stored = f.attrs.get(DIGEST)
        if stored is None:
            raise ResultFileError(path, "no checksum: the file was not completely written")
        if stored != digest(f):
            raise ResultFileError(
                path,
                "damaged: its contents do not match the checksum stored when it was written",
            )


def digest(f: Any) -> str:
    """SHA-256 of an HDF5 file's contents: every attribute (but the checksum) and dataset.

    Objects are visited by name in sorted order and every item is length-prefixed, so the
    digest depends on the contents only, not on where HDF5 put them in the file. A dataset's
    dimension scales count by their names (their HDF5 attributes hold addresses); a file
    without them (format version 2) digests as it always did.
    """
    import h5py

    h = hashlib.sha256()

    def add(data: bytes) -> None:
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)

    def visit(obj: Any, name: str) -> None:
        add(name.encode())
        for key in sorted(obj.attrs):
            if (name == "/" and key == DIGEST) or key in _SCALE_ATTRIBUTES:
                continue
            add(key.encode())
            add(_value_bytes(obj.attrs[key]))
        if isinstance(obj, h5py.Dataset):
            if "DIMENSION_LIST" in obj.attrs:
                add(b"dims" + json.dumps(_scale_names(obj)).encode())
            add(_value_bytes(obj[()]))
        else:
            for key in sorted(obj):
                visit(obj[key], f"{name.rstrip('/')}/{key}")

    visit(f, "/")
    return h.hexdigest()


def _scale_names(ds: Any) -> list[list[str]] | str:
    """The names of the dimension scales attached to each axis of ``ds``; ``"unresolved"``
    when a reference leads nowhere (a scale deleted after it was attached), which the
    reading then reports as the missing dataset it is."""
    try:
        return [[scale.name for scale in dim.values()] for dim in ds.dims]
    except (RuntimeError, KeyError, ValueError, OSError):
        return "unresolved"


def _value_bytes(value: Any) -> bytes:
    if isinstance(value, str):
        return b"s" + value.encode("utf-8", "surrogatepass")
    if isinstance(value, bytes):
        return b"b" + value
    arr = np.asarray(value)
    if arr.dtype == object:
        parts = [_value_bytes(v) for v in arr.ravel()]
        return (
            b"o"
            + json.dumps(arr.shape).encode()
            + b"".join(len(p).to_bytes(8, "little") + p for p in parts)
        )
    return arr.dtype.str.encode() + json.dumps(arr.shape).encode() + arr.tobytes()
