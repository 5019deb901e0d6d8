"""Output directories that cannot hurt anyone: ownership manifests, write probes, leftovers.

inserr deletes or overwrites only files it wrote itself. Every directory it writes
as a whole (a report) or keeps writing into (a sweep) holds a *marker* file whose
JSON *manifest* names what inserr wrote there:

* a report's marker (``.inserr-report``) lists every file of the report with its
  SHA-256, so a file the user added *or edited* since is noticed;
* a resumable store's marker (a sweep's ``.inserr-sweep``) lists the files it
  rewrites in place (names only) and the sub-directories it fills, each with the
  pattern of the file names inserr gives there (``points/<16 hex digits>.json``). A
  store adds a name to its manifest *before* writing the file, so the manifest is
  always a superset of what inserr has written, even after a kill.

:func:`foreign_entry` compares a directory with its manifest and names the first
entry that inserr cannot prove it wrote; :func:`check_output_dir` refuses such a
directory (and the working directory, a file, a directory holding the run's own
input files, an unwritable place) *before any work*.

Interrupted writes leave nothing that can be mistaken for a result: files and
directories are written under temporary names ``.<name>.tmp-<pid>-<random>`` and
renamed into place when complete. A run killed outright (SIGKILL, power loss)
leaves such a temporary behind; the next run into the same place removes it, but
only when it can prove the leftover is inserr's (the name pattern, a writer process
that no longer runs, and for a directory the tag file :data:`TMP_TAG` or a marker
whose manifest covers everything in it) — see :func:`clean_leftovers`.

Write permission is checked by creating and removing a probe file
(``.inserr-probe-<pid>-<random>``) where the run will write, rather than by
:func:`os.access`: as root, permission bits do not apply but a read-only mount
still refuses, and only an attempt tells.
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import secrets
import shutil
import socket
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

from inserr.core.errors import InputError

#: Version of the manifest format written into markers.
MANIFEST_FORMAT = 1

#: Tag file inside a temporary directory inserr is filling (holds the writer's pid and host).
TMP_TAG = ".inserr-tmp"

#: Names of temporaries: ``.<name>.tmp-<pid>-<random>`` (being written) and
#: ``.<name>.old-<pid>-<random>`` (a replaced report on its way out).
_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<kind>tmp|old)-(?P<pid>\d+)-[A-Za-z0-9_]+$")
_PROBE = re.compile(r"^\.inserr-probe-(?P<pid>\d+)-[A-Za-z0-9_]+$")


@dataclass(frozen=True)
class Manifest:
    """What inserr wrote into one directory (the content of its marker file).

    Attributes
    ----------
    kind : str
        What the directory is (``"report"``, ``"sweep"``).
    files : dict of str to (str or None)
        Top-level file name -> SHA-256 (hex) of the content inserr wrote, or None for
        a file a store rewrites in place (only its name is recorded).
    dirs : dict of str to str
        Sub-directory -> regular expression that every file name inside must match.
    legacy : bool
        The marker predates manifests (plain text): no list, see :func:`foreign_entry`.
    """

    kind: str
    files: dict[str, str | None] = field(default_factory=dict)
    dirs: dict[str, str] = field(default_factory=dict)
    legacy: bool = False

    def text(self) -> str:
        """The marker's content: the manifest as JSON text."""
        return (
            json.dumps(
                {
                    "written_by": "inserr",
                    "format": MANIFEST_FORMAT,
                    "kind": self.kind,
                    "files": dict(sorted(self.files.items())),
                    "dirs": dict(sorted(self.dirs.items())),
                },
                indent=1,
            )
            + "\n"
        )

    def with_files(self, names: Iterable[str]) -> Manifest:
        """A copy that also lists ``names`` (recorded without a digest)."""
        files = dict(self.files)
        for n in names:
            files.setdefault(n, None)
        return Manifest(self.kind, files, dict(self.dirs))


def sha256(data: bytes) -> str:
    """SHA-256 of ``data`` as hex (the digest a report's manifest records)."""
    return hashlib.sha256(data).hexdigest()


def _file_sha256(path: Path) -> str | None:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
    except OSError:
        return None
    return h.hexdigest()


def read_manifest(directory: Path, marker: str) -> Manifest | None:
    """The manifest in ``directory/marker``; None when there is no marker file.

    A marker that is not a JSON manifest (written by inserr before manifests
    existed: one line of text) gives a :attr:`Manifest.legacy` manifest; a marker
    that cannot be read at all (a directory, unreadable, another program's JSON)
    gives None, so the directory is not taken for inserr's.
    """
    path = directory / marker
    if path.is_symlink() or not path.is_file():
        return None
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    if text.startswith("written by inserr"):
        return Manifest(kind="", legacy=True)
    try:
        data = json.loads(text)
    except ValueError:
        return None
    if not isinstance(data, dict) or data.get("written_by") != "inserr":
        return None
    files, dirs = data.get("files"), data.get("dirs", {})
    if not isinstance(files, dict) or not isinstance(dirs, dict):
        return None
    if not all(isinstance(k, str) and (v is None or isinstance(v, str)) for k, v in files.items()):
        return None
    if not all(isinstance(k, str) and isinstance(v, str) for k, v in dirs.items()):
        return None
    return Manifest(str(data.get("kind", "")), dict(files), dict(dirs))


def write_manifest(directory: Path, marker: str, manifest: Manifest) -> None:
    """Write the marker file atomically."""
    write_bytes_atomic(directory / marker, manifest.text().encode("utf-8"))


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # another user's process (or a number no process has): keep
    return True


def _is_temp_entry(name: str) -> bool:
    """An inserr temporary or probe name (whatever the state of its writer)."""
    return bool(_TEMP.match(name) or _PROBE.match(name))


def foreign_entry(
    directory: Path,
    marker: str,
    *,
    legacy: Callable[[Path], bool] | None = None,
    also_ours: Callable[[Path], bool] | None = None,
) -> tuple[str, str] | None:
    """The first entry of ``directory`` that inserr cannot prove it wrote, and why.

    An entry is inserr's when the manifest in ``marker`` lists it (a regular file,
    with the same SHA-256 when one is recorded), when it is a file inside a listed
    sub-directory whose name matches that directory's pattern, when ``also_ours``
    says so (e.g. a PNG carrying the sweep's figure mark), or when it is one of
    inserr's temporaries (:func:`clean_leftovers` removes those). With a legacy
    marker (no list), ``legacy(path)`` decides for each top-level entry.

    Parameters
    ----------
    directory : Path
        An existing directory.
    marker : str
        Name of its marker file.
    legacy : callable, optional
        ``legacy(path) -> bool`` for the entries of a directory with a legacy marker;
        without it, a legacy marker proves nothing.
    also_ours : callable, optional
        ``also_ours(path) -> bool``: top-level entries proven inserr's by content.

    Returns
    -------
    (str, str) or None
        The entry's path relative to ``directory`` and the reason, in name order;
        None if everything is inserr's.
    """
    manifest = read_manifest(directory, marker)
    entries = sorted(os.scandir(directory), key=lambda e: e.name)
    if manifest is None:
        for e in entries:
            return e.name, "which inserr did not write (the directory has no inserr marker)"
        return None
    for e in entries:
        name, path = e.name, Path(e.path)
        if name == marker or _is_temp_entry(name):
            continue
        if also_ours is not None and e.is_file(follow_symlinks=False) and also_ours(path):
            continue
        if manifest.legacy:
            if legacy is not None and legacy(path):
                continue
            return name, "which inserr did not write"
        if name in manifest.files:
            if not e.is_file(follow_symlinks=False):
                return name, "which is not the file inserr wrote under that name"
            digest = manifest.files[name]
            if digest is not None and _file_sha256(path) != digest:
                return name, "which was changed since inserr wrote it"
            continue
        if name in manifest.dirs and e.is_dir(follow_symlinks=False):
            pattern = re.compile(manifest.dirs[name])
            for sub in sorted(os.scandir(path), key=lambda s: s.name):
                if _is_temp_entry(sub.name):
                    continue
                if not (sub.is_file(follow_symlinks=False) and pattern.fullmatch(sub.name)):
                    return f"{name}/{sub.name}", "which inserr did not write"
            continue
        return name, "which inserr did not write"
    return None


def temp_prefix(name: str) -> str:
    """Prefix of a temporary for ``name``: ``.<name>.tmp-<pid>-`` (a random tail follows)."""
    return f".{name}.tmp-{os.getpid()}-"


def old_name(name: str) -> str:
    """A fresh name for a replaced directory on its way out: ``.<name>.old-<pid>-<random>``."""
    return f".{name}.old-{os.getpid()}-{secrets.token_hex(4)}"


def tag_temp_dir(path: Path) -> None:
    """Write :data:`TMP_TAG` into a temporary directory inserr has just created."""
    (path / TMP_TAG).write_text(f"{os.getpid()} {socket.gethostname()}\n", encoding="utf-8")


def _tagged_by_this_host(path: Path) -> bool:
    try:
        _, host = (path / TMP_TAG).read_text(encoding="utf-8").split()
    except (OSError, ValueError, UnicodeDecodeError):
        return False
    return host == socket.gethostname()


def clean_leftovers(
    directory: Path, names: Iterable[str] | None = None, marker: str | None = None
) -> list[Path]:
    """Remove the temporaries of killed inserr runs from ``directory``; return them.

    Removed: files and directories named ``.<name>.tmp-<pid>-*`` or
    ``.<name>.old-<pid>-*`` (``name`` one of ``names``; any name if None) and probe
    files, whose process ``pid`` no longer runs, and, for a directory, that carries
    :data:`TMP_TAG` written on this host or the ``marker`` of a manifest covering
    everything in it. Anything else is left alone, however it is named.

    Parameters
    ----------
    directory : Path
    names : iterable of str, optional
        The final names the temporaries were for.
    marker : str, optional
        The marker a finished (but not yet renamed, or replaced) directory holds.

    Returns
    -------
    list of Path
        What was removed.
    """
    wanted = None if names is None else set(names)
    removed: list[Path] = []
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for e in entries:
        m = _TEMP.match(e.name) or _PROBE.match(e.name)
        if m is None or _pid_alive(int(m["pid"])):
            continue
        if "name" in m.groupdict() and wanted is not None and m["name"] not in wanted:
            continue
        path = Path(e.path)
        try:
            if e.is_symlink():
                continue
            if e.is_file():
                path.unlink()
            elif e.is_dir():
                ours = _tagged_by_this_host(path) or (
                    marker is not None
                    and read_manifest(path, marker) is not None
                    and not read_manifest(path, marker).legacy
                    and foreign_entry(path, marker) is None
                )
                if not ours:
                    continue
                shutil.rmtree(path)
            else:
                continue
        except OSError:
            continue
        removed.append(path)
    return removed


def is_mount_point(path: Path) -> bool:
    """Whether ``path`` is a mount point, bind mounts included (which cannot be renamed).

    :func:`os.path.ismount` misses a bind mount of a directory of the same file
    system; on Linux the mount table of this process (``/proc/self/mountinfo``)
    lists them all.
    """
    if os.path.ismount(path):
        return True
    try:
        table = Path("/proc/self/mountinfo").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False
    target = str(Path(path).resolve())
    for line in table.splitlines():
        parts = line.split()
        if len(parts) > 4:
            # Field 5 is the mount point, with blanks and backslashes octal-escaped.
            point = re.sub(r"\\([0-7]{3})", lambda m: chr(int(m[1], 8)), parts[4])
            if point == target:
                return True
    return False


def probe_writable(directory: Path, field: str) -> None:
    """Create and remove a probe file in ``directory``, or raise InputError naming ``field``.

    An attempt rather than :func:`os.access`, which a root user always passes even
    on a read-only mount.
    """
    probe = directory / f".inserr-probe-{os.getpid()}-{secrets.token_hex(4)}"
    try:
        fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        why = {
            errno.EROFS: "it is on a read-only file system",
            errno.EACCES: "no permission to write there",
            errno.EPERM: "no permission to write there",
            errno.ENOSPC: "the disk is full",
            errno.EDQUOT: "the disk quota is exhausted",
        }.get(exc.errno, exc.strerror or str(exc))
        raise InputError(
            field, f"cannot write in {directory} ({why})", "choose a writable directory"
        ) from None


def check_output_dir(
    out_dir: str | os.PathLike,
    field: str,
    is_ours: Callable[[Path], bool],
    what: str,
    fix: str,
    *,
    marker: str | None = None,
    legacy: Callable[[Path], bool] | None = None,
    also_ours: Callable[[Path], bool] | None = None,
    replaces_whole: bool = False,
    inputs: Iterable[str | os.PathLike] = (),
) -> Path:
    """Check, before any work, that inserr may write into ``out_dir``; return it resolved.

    Refused, each with one line naming ``field``, the cause and the fix:

    * the working directory or one of its parents, a file, a path through a file;
    * a directory holding one of the run's own ``inputs`` (the scenario file);
    * a non-empty directory holding an entry inserr did not write: with the
      ``marker`` present, the first entry its manifest does not cover
      (:func:`foreign_entry`); without it, unless ``is_ours(path)`` (the rule of an
      older layout) is true, the first entry;
    * a place where a probe file cannot be created (:func:`probe_writable`): the
      directory itself if it exists, else its nearest existing parent; with
      ``replaces_whole`` also the parent (the replacement is built there), and a
      mount point (which cannot be renamed).

    Parameters
    ----------
    out_dir : str or path
        The output directory the user asked for.
    field : str
        Name of the flag or key reported in the error message.
    is_ours : callable
        ``is_ours(path)`` for a non-empty directory without ``marker``: True when it
        is provably inserr's in an older layout (without one, return False).
    what : str
        What the directory is meant to be, for the message (e.g. "an inserr report").
    fix : str
        How to fix a refused directory.
    marker, legacy, also_ours
        The marker file's name and the rules of :func:`foreign_entry`.
    replaces_whole : bool
        The directory is replaced as a whole (a report), not written into.
    inputs : iterable of path
        Files the run reads; none may be inside ``out_dir``.

    Returns
    -------
    Path
        The resolved target.

    Raises
    ------
    InputError
        If writing there could destroy files inserr did not write, or cannot succeed.
    """
    target = Path(out_dir).expanduser().resolve()
    cwd = Path.cwd().resolve()
    shown = str(out_dir)
    if target == cwd or target in cwd.parents:
        raise InputError(
            field,
            f"{shown} is the working directory or one of its parents",
            "name a new directory, e.g. my_report",
        )
    if target.exists() and not target.is_dir():
        raise InputError(field, f"{shown} exists and is not a directory", "name a directory")
    for inp in inputs:
        p = Path(inp).expanduser().resolve()
        if target in p.parents:
            raise InputError(
                field,
                f"{shown} holds the input file {p.relative_to(target)} of this run",
                f"write elsewhere, e.g. {target.name}_out (the input is never touched)",
            )
    if target.is_dir():
        if any(target.iterdir()):
            has_marker = marker is not None and read_manifest(target, marker) is not None
            if has_marker:
                bad = foreign_entry(target, marker, legacy=legacy, also_ours=also_ours)
            elif is_ours(target):
                bad = None
            else:
                first = sorted(p.name for p in target.iterdir())[0]
                bad = (first, f"which inserr did not write (it is not {what} directory)")
            if bad is not None:
                name, why = bad
                raise InputError(field, f"{shown} holds {name}, {why}", fix)
        if replaces_whole and is_mount_point(target):
            raise InputError(
                field,
                f"{shown} is a mount point, which a report (replaced as a whole) cannot replace",
                "name a new directory inside it",
            )
        probe_writable(target, field)
        if replaces_whole:
            probe_writable(target.parent, field)
        return target
    for parent in target.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(
                    field, f"{parent} is a file, so {shown} cannot be created", "fix the path"
                )
            probe_writable(parent, field)
            break
    return target


def write_bytes_atomic(path: str | os.PathLike, data: bytes) -> None:
    """Write a file atomically (temporary file in the same directory, then rename).

    The temporary is named ``.<name>.tmp-<pid>-<random>`` (:func:`temp_prefix`), so a
    kill mid-write leaves a name :func:`clean_leftovers` recognizes. The file ends
    up world-readable (0644), like any other output.
    """
    import tempfile

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temp_prefix(path.name), dir=path.parent)
    try:
        os.chmod(tmp, 0o644)  # mkstemp makes it private; results are meant to be read
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
