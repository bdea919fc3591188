"""Our files on disk: where they may be written, how they are written, how they are checked.

Every file the commands write (result, reference, sweep and check files, plots) follows one
policy (docs/scenes.md, "Files"):

* **Destination checked first.** Before any work, :func:`check_destination` refuses a missing
  or read-only directory, a directory given as the file, and an existing file that is not one
  of ours of the same kind (unless ``overwrite``), or, for a caller that says what the file
  will hold (``holding``), one that holds another scene or study. A result file of ours of the
  same scene is replaced: running the same command again is the usual way to redo a run, and
  the old file survives until the new one is complete.
* **Atomic.** :func:`write_bytes` is the one writer: it writes ``.NAME.tmp-PID`` beside the
  file (created afresh: processes never share one), flushes it to disk and renames it over
  the file, so a process killed at any moment leaves the previous file or the new one, never
  a mixture. A failed write (a full disk) removes its temporary and raises
  :class:`WriteFailed`; one left by a killed process is removed by the next write to the same
  name. HDF5 files are built in memory and written by it (:func:`write_hdf5`).
* **Whole under a signal.** SIGINT and SIGTERM are held from the start of a write to the
  rename and delivered after it: a Ctrl-C during a save takes effect once the file is in
  place.
* **Checksummed.** HDF5 files carry the SHA-256 of their contents (every attribute and every
  dataset, in a fixed order) in the root attribute ``sha256``; :func:`open_ours` verifies it,
  so a damaged file is refused instead of read as NaNs, and a file rewritten by another
  program (xarray's ``to_netcdf``) is refused as such. Files of format version 1 (before the
  checksum) are still read, unchecked.
* **Checkpoints too.** The files of an interrupted computation's work directory
  (:func:`write_checkpoint`) go through the same writer; each carries a checksum and the
  identity of the run it belongs to, verified when it is read (:func:`read_checkpoint`).
"""

from __future__ import annotations

import contextlib
import errno
import glob
import hashlib
import json
import os
from collections.abc import Callable, Collection, Iterator
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
    after the work it was to save: a command reports it as a stop (exit 1), not a refusal,
    and shows what it computed (``result``, where the writer's caller attaches it)."""

    result: Any = None


# ---------------------------------------------------------------------- destinations
def check_destination(
    path: str | Path,
    kind: str,
    *,
    overwrite: bool = False,
    holding: tuple[str, Any] | None = None,
    ignoring: Collection[str] = (),
) -> None:
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
    holding
        ``(attribute, value)``: what the new file will hold (``("scene", scene.to_dict())``,
        ``("study", ...)``). A file of ours of this kind is then replaced only if its
        attribute holds the same (JSON) value: a re-run of the same scene, never another
        scene's result.
    ignoring
        Top-level keys of that value not compared (a reference's ``integrator``, which it
        chooses itself).

    Raises
    ------
    OutputError
        Naming the path and the rule: the directory is missing, not a directory or not
        writable; the path is a directory or a special file; or an existing file is not ours
        of this kind (or, with ``holding``, holds something else) and ``overwrite`` is not
        set.
    """
    given = Path(path)
    try:
        _check_destination(given, kind, overwrite, holding, ignoring)
    except OSError as exc:  # a name too long, a loop of links, ...
        raise OutputError(given, f"cannot be written ({_reason(exc)})") from exc


def _check_destination(
    given: Path,
    kind: str,
    overwrite: bool,
    holding: tuple[str, Any] | None,
    ignoring: Collection[str] = (),
) -> None:
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
    if holding is not None and (other := _holds_other(target, *holding, ignoring)) is not None:
        raise OutputError(
            given,
            f"exists and holds the {kind} of another {holding[0]} ({other}); refusing to "
            "replace it (choose another name, or pass --overwrite)",
        )


def _holds_other(target: Path, attribute: str, value: Any, ignoring: Collection[str]) -> str | None:
    """How the file's ``attribute`` differs from ``value`` (its title, or the first key that
    differs), or None if it holds the same."""
    import h5py

    try:
        with h5py.File(target, "r") as f:
            stored = json.loads(f.attrs.get(attribute, "null"))
    except Exception:  # noqa: BLE001 -- identified as ours just before: unreadable now
        return f"its {attribute} cannot be read"
    ours = json.loads(json.dumps(value))
    if isinstance(stored, dict) and isinstance(ours, dict):
        stored, ours = ({k: v for k, v in d.items() if k not in ignoring} for d in (stored, ours))
    if stored == ours:
        return None
    if not isinstance(stored, dict) or not isinstance(ours, dict):
        return f"its {attribute} is not this one"
    theirs, mine = stored.get("title"), ours.get("title")
    if theirs != mine:
        return f"title {theirs!r}, not {mine!r}"
    key = next(k for k in sorted({*stored, *ours}) if stored.get(k) != ours.get(k))
    return f"{theirs!r}, with another [{key}]"


def file_id(path: str | Path) -> tuple[int, int] | None:
    """Which file ``path`` is now (device, inode), None if none: a file written since, by
    :func:`write_bytes`, is another one."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return (st.st_dev, st.st_ino)


def identify(path: str | Path) -> str | None:
    """Which kind of our files ``path`` is (``"result"``, ... ``"plot"``), or None."""
    path = Path(path)
    try:
        if not path.is_file():  # opening a FIFO would wait for a writer; a device may never end
            return None
        with open(path, "rb") as f:
            head = f.read(8)
    except OSError:  # unreadable, a name too long: not a file of ours (the reader says why)
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
def write_bytes(path: str | Path, data: bytes | memoryview) -> None:
    """Write ``data`` as the file ``path``, atomically: the one way our files reach the disk.

    The bytes go to ``.NAME.tmp-PID`` beside the file (created afresh, so two processes, or
    two threads, never share one), are flushed to disk and renamed over the file. SIGINT and
    SIGTERM are held from the first byte to the rename (:func:`~.signals.held_signals`): a
    Ctrl-C during the write takes effect once the file is in place.

    Raises
    ------
    WriteFailed
        When writing fails (a full disk, a vanished directory): the temporary is removed and
        the file at ``path``, if any, is as it was.
    """
    from .signals import held_signals

    path = Path(path)
    target = Path(os.path.realpath(path))
    with held_signals():
        _remove_stale(target)
        tmp, fd = _create_temporary(path, target)
        try:
            try:
                view = memoryview(data).cast("B")
                while view:
                    view = view[os.write(fd, view) :]
                os.fsync(fd)
            finally:
                os.close(fd)
            os.replace(tmp, target)
        except OSError as exc:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise OutputError.failed_write(path, exc) from exc
        except BaseException:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise
        _fsync_directory(target.parent)


def _create_temporary(path: Path, target: Path) -> tuple[Path, int]:
    """A new temporary beside ``target``, open for writing: ``.NAME.tmp-PID``, or
    ``.NAME.tmp-PID-N`` when this process is already writing the first (another thread)."""
    base = f".{target.name}.tmp-{os.getpid()}"
    for n in range(1, 1000):
        tmp = target.with_name(base if n == 1 else f"{base}-{n}")
        try:
            return tmp, os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            continue
        except OSError as exc:
            raise OutputError.failed_write(path, exc) from exc
    raise OutputError(path, f"could not be written (999 temporaries {base}-N exist)")


def write_hdf5(path: str | Path, fill: Callable[[Any], None]) -> None:
    """Write an HDF5 file atomically: ``fill(h5py_file)``, then its checksum.

    The file is built in memory and then written by :func:`write_bytes`: HDF5 itself never
    writes to the disk, where a full disk would leave it half-closed (tracebacks from its
    destructors, even a crash). Costs memory of the file's size while it is written (a result
    of 10⁶ rows of 8 variables: 64 MB, built in ~0.1 s).
    """
    import io

    import h5py

    from .signals import held_signals

    with held_signals():  # the file as it was when asked for: a signal does not cut it short
        image = io.BytesIO()
        try:
            # Creation order kept, as netCDF-4 keeps it: readers list variables as written.
            with h5py.File(image, "w", track_order=True) as f:
                fill(f)
                seal(f)
        except OSError as exc:  # HDF5 out of memory; nothing was written
            raise OutputError.failed_write(path, exc) from exc
        write_bytes(path, image.getbuffer())


def seal(f: Any) -> None:
    """Store the checksum of an open HDF5 file's contents (the last thing written)."""
    f.attrs[DIGEST] = digest(f)


def _remove_stale(target: Path) -> None:
    prefix = f".{target.name}.tmp-"
    with contextlib.suppress(OSError):
        for tmp in target.parent.glob(f"{glob.escape(prefix)}*"):
            pid = tmp.name[len(prefix) :].split("-")[0]
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


# ---------------------------------------------------------------------- checkpoints
#: First line of every checkpoint file (:func:`write_checkpoint`).
CHECKPOINT_MAGIC = b"cayley_heyoka checkpoint 1\n"


class CheckpointError(ValueError):
    """A checkpoint file that cannot be used: ``reason`` says whether it is ``"missing"``,
    ``"damaged"`` (not a checkpoint, cut short, edited: its checksum differs) or ``"foreign"``
    (whole, but written for another run, or as another of its files).

    Parameters
    ----------
    path
        The file.
    reason
        ``"missing"``, ``"damaged"`` or ``"foreign"``.
    what
        What is wrong with it.
    """

    def __init__(self, path: str | Path, reason: str, what: str, found: bytes = b"") -> None:
        self.path = Path(path)
        self.reason = reason
        self.what = what
        #: The body of a ``"foreign"`` file (to say how it differs).
        self.found = found
        super().__init__(f"{path}: {what}")


def identity_of(data: Any) -> str:
    """The SHA-256 of JSON-ready ``data`` written canonically (sorted keys, no spaces): what a
    checkpoint file names the run it belongs to by."""
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()


def write_checkpoint(path: str | Path, kind: str, identity: str, body: bytes, **fields: Any) -> str:
    """Write a checkpoint file through :func:`write_bytes` and return the digest of its body.

    The file is :data:`CHECKPOINT_MAGIC`, one line of JSON — its ``kind``, the ``identity``
    of the run it belongs to, the body's size and the ``fields`` (JSON-ready), sealed by a
    SHA-256 of both header and body — and the body. :func:`read_checkpoint` verifies all.
    """
    body_digest = hashlib.sha256(body).hexdigest()
    header = {
        **fields,
        "kind": kind,
        "identity": identity,
        "size": len(body),
        "body_sha256": body_digest,
    }
    text = json.dumps(header, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    line = text.encode()
    seal_ = hashlib.sha256(line + b"\n" + body).hexdigest()
    write_bytes(path, CHECKPOINT_MAGIC + seal_.encode() + b" " + line + b"\n" + body)
    return body_digest


def read_checkpoint(path: str | Path, kind: str, identity: str) -> tuple[dict[str, Any], bytes]:
    """The header fields and the body of a checkpoint file, verified.

    Raises
    ------
    CheckpointError
        ``"missing"``: no such file; ``"damaged"``: not a checkpoint file, cut short or
        edited; ``"foreign"``: whole, but of another ``kind`` or another run's ``identity``.
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:
            data = f.read()
    except FileNotFoundError:
        raise CheckpointError(path, "missing", "is missing") from None
    except OSError as exc:
        raise CheckpointError(path, "damaged", f"cannot be read ({_reason(exc)})") from exc
    if not data.startswith(CHECKPOINT_MAGIC):
        raise CheckpointError(path, "damaged", "is not a checkpoint file of cayley_heyoka")
    seal_, _, rest = data[len(CHECKPOINT_MAGIC) :].partition(b" ")
    line, newline, body = rest.partition(b"\n")
    if not newline or hashlib.sha256(line + b"\n" + body).hexdigest().encode() != seal_:
        raise CheckpointError(
            path, "damaged", "is damaged (cut short or edited: its checksum differs)"
        )
    try:
        header = json.loads(line)
    except ValueError:
        header = None
    if not isinstance(header, dict) or header.get("size") != len(body):
        raise CheckpointError(path, "damaged", "is damaged (its header is not ours)")
    if header.get("kind") != kind:
        raise CheckpointError(
            path, "foreign", f"is a checkpoint {header.get('kind')!r}, not a {kind!r}"
        )
    if header.get("identity") != identity:
        raise CheckpointError(
            path, "foreign", "belongs to another run (its identity differs)", body
        )
    return header, body


@contextlib.contextmanager
def locked_directory(directory: str | Path, name: str, user: str) -> Iterator[None]:
    """Hold ``directory`` for this process, or refuse it at once if another process holds it.

    An exclusive ``flock`` on the file ``name`` in it, which names the holder's process; the
    file is removed when the context ends. A lock held by a process that was killed ends with
    it (the kernel releases it).

    Raises
    ------
    OutputError
        Another process holds the directory (naming it and ``user``, what it runs), or the
        lock file cannot be made.
    """
    import fcntl

    directory = Path(directory)
    path = directory / name
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise OutputError(directory, f"cannot be locked ({_reason(exc)})") from exc
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = ""
            with contextlib.suppress(OSError, ValueError):
                holder = f" (process {int(os.pread(fd, 32, 0).decode().split()[0])})"
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise OutputError(
                    directory,
                    f"is in use by another {user}{holder}; wait for it to end, or give this "
                    "one another --out",
                ) from None
            raise OutputError(directory, f"cannot be locked ({_reason(exc)})") from exc
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except OSError:
            same = False
        if same:
            break
        os.close(fd)  # the holder before us removed the file we locked: lock the new one
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
    except OSError:
        pass  # the pid only makes a refusal clearer; a full disk must not stop the lock
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            path.unlink()
        os.close(fd)


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
    try:
        exists, is_dir, is_file = path.exists(), path.is_dir(), path.is_file()
    except OSError as exc:  # a name too long, a loop of links, no permission on the way
        raise ResultFileError(path, f"cannot be read ({_reason(exc)})") from None
    if not exists:
        raise ResultFileError(path, "no such file")
    if is_dir:
        raise ResultFileError(path, "is a directory, not a file")
    if not is_file:
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
    rewritten = _rewritten(f)
    if rewritten:
        raise ResultFileError(
            path,
            f"was rewritten by another program{rewritten}; cayley_heyoka reads only the "
            "files it wrote (open this one with the program that rewrote it)",
        )
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


def _rewritten(f: Any) -> str:
    """Why the root attributes of ``f`` look like one of our files rewritten by another
    program (as ``xarray.Dataset.to_netcdf`` writes them), or '' if they do not."""
    fmt, version = f.attrs.get("format"), f.attrs.get("format_version")
    if isinstance(fmt, bytes | np.bytes_):
        fmt = fmt.decode("utf-8", "replace")
    if fmt not in FORMATS.values():
        return ""
    what = []
    if isinstance(f.attrs.get("format"), bytes | np.bytes_):
        what.append("format is bytes, not text")
    if isinstance(version, np.ndarray):
        what.append("format_version is an array, not a number")
    if not what:
        return ""
    by = f.attrs.get("_NCProperties")
    if isinstance(by, bytes | np.bytes_):
        by = by.decode("utf-8", "replace")
    who = f" ({by})" if isinstance(by, str) and by else ""
    return f"{who}: its attributes are not ours ({'; '.join(what)})"


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
