"""Checking files on a Ray cluster, no shared file system assumed.

Each file goes as a task with a snapshot of its folder (what it can reference is inside it:
:func:`cellengine.info.files.resolve_inside`): regular files with their bytes, links with
their targets. The worker rebuilds the folder at the same absolute path under a temporary
root, works from the same working folder under it, checks the file as one process would,
and takes the root back out of every path in the answer, so messages read exactly as a local
check's. Folders that hold a run (a ``.lock``) and hidden entries are not sent.
"""

from __future__ import annotations

import logging
import os
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

from cellengine.cache import engine_fingerprint
from cellengine.checker import Result
from cellengine.errors import Problem, UsageError
from cellengine.info.files import real
from cellengine.runfolder import LOCK
from cellengine.workers import Crashed, Raised

# A snapshot: each entry's absolute path -> its bytes, or ("link", target) for a link.
Snapshot = dict[str, bytes | tuple[str, str]]
MAX_SNAPSHOT_BYTES = 512 << 20
T = TypeVar("T")
R = TypeVar("R")


# Ray Client's proxy forks a server for each connection, and that server sometimes dies at
# birth (ray-project/ray#63202: a gRPC poller race in the fork); a new connection works.
CONNECT_ATTEMPTS = 4
SERVER_DIED = "Starting Ray client server failed"


def connect(address: str, pause: float = 2.0) -> Any:
    """The ray module, connected to the cluster at ``address``."""
    try:
        import ray
    except ImportError:
        raise UsageError(
            Problem("--cluster needs Ray: pip install 'cellengine[cluster]'")
        ) from None
    attempt = 1
    while True:
        try:
            ray.init(address=address, logging_level=logging.ERROR, log_to_driver=False)
            return ray
        except Exception as e:  # Ray's own: ConnectionError, ValueError, RuntimeError...
            if SERVER_DIED not in str(e) or attempt == CONNECT_ATTEMPTS:
                why = f"cannot reach the Ray cluster at '{address}': {e}"
                raise UsageError(Problem(why)) from None
        ray.shutdown()
        time.sleep(pause)
        attempt += 1


def on_cluster(
    address: str, tasks: Sequence[tuple[Path, T]], fn: Callable[[T], R]
) -> Iterator[tuple[int, R | Crashed | Raised]]:
    """``fn(arg)`` on the cluster for each (file, arg) of ``tasks``, with a snapshot of the
    file's folder rebuilt around it; (index, answer) in the tasks' order."""
    if not tasks:
        return
    ray = connect(address)
    try:
        remote = ray.remote(max_retries=0, num_cpus=1)(run_shipped)
        folders: dict[Path, Any] = {}
        refs = []
        for f, arg in tasks:
            folder = real(f).parent
            if folder not in folders:  # one snapshot for the files of a folder
                folders[folder] = ray.put(snapshot(folder))
            refs.append(remote.remote(folders[folder], os.getcwd(), fn, arg))
        for k, ref in enumerate(refs):
            yield k, _answer(ray, ref)
    finally:
        ray.shutdown()


def _answer(ray: Any, ref: Any) -> Any:
    try:
        engine, answer = ray.get(ref)
    except ray.exceptions.RayTaskError as e:  # the task raised: a defect
        return Raised(None, str(e))
    except ray.exceptions.RayError as e:  # the worker or its node died
        return Crashed(f"its Ray worker died ({type(e).__name__})")
    if engine != engine_fingerprint():
        raise UsageError(
            Problem(
                "the Ray cluster runs another cellengine (its code or libraries differ "
                "from this one's); install this one on its nodes"
            )
        )
    return answer


def snapshot(folder: Path) -> Snapshot:
    """``folder``'s regular files and links, by absolute path, less hidden entries and run
    folders (what a check can read: references are resolved inside the folder)."""
    out: Snapshot = {}
    total = 0
    for top, dirs, files in os.walk(folder):  # links to folders are listed, not walked
        dirs[:] = [d for d in dirs if not d.startswith(".") and not Path(top, d, LOCK).exists()]
        for name in sorted(n for n in files if not n.startswith(".")) + sorted(dirs):
            path = Path(top, name)
            if path.is_symlink():
                out[str(path)] = ("link", os.readlink(path))
            elif path.is_file():
                total += path.stat().st_size
                if total > MAX_SNAPSHOT_BYTES:
                    raise UsageError.at(
                        f"the folder holds more than {MAX_SNAPSHOT_BYTES >> 20} MB to send "
                        "to the cluster; keep a cell's folder to its files",
                        folder,
                    )
                out[str(path)] = path.read_bytes()
    return out


def run_shipped(files: Snapshot, cwd: str, fn: Callable[[T], R], arg: T) -> tuple[str, R]:
    """On a worker: ``fn(arg)`` in the rebuilt ``files``, from ``cwd`` rebuilt there; the
    engine's fingerprint and the answer, its paths as the sender's."""
    with tempfile.TemporaryDirectory(prefix="cellengine-") as tmp:
        root = real(Path(tmp))
        for path, content in files.items():
            here = root / path.lstrip("/")
            here.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, tuple):
                here.symlink_to(content[1])
            else:
                here.write_bytes(content)
        work = root / cwd.lstrip("/")
        work.mkdir(parents=True, exist_ok=True)
        before = os.getcwd()
        os.chdir(work)
        try:
            answer = fn(arg)
        finally:
            os.chdir(before)
        return engine_fingerprint(), _sent_back(answer, str(root))


def _sent_back(answer: Any, root: str) -> Any:
    """``answer`` with the temporary root taken out of every path and text in it."""
    if isinstance(answer, str):
        return answer.replace(root, "")
    if isinstance(answer, Path):
        return Path(str(answer).replace(root, ""))
    if isinstance(answer, list | tuple):
        return type(answer)(_sent_back(a, root) for a in answer)
    if isinstance(answer, dict):
        return {_sent_back(k, root): _sent_back(v, root) for k, v in answer.items()}
    if isinstance(answer, Problem):
        return Problem(
            _sent_back(answer.message, root), _sent_back(answer.file, root), answer.line, answer.col
        )
    if isinstance(answer, Result):
        return Result(
            answer.file,
            answer.kind,
            _sent_back(answer.problems, root),
            _sent_back(answer.warnings, root),
            _sent_back(answer.reads, root),
        )
    return answer
