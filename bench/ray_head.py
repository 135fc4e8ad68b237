"""A Ray head on the loopback address for the tests and benchmarks: `ray start --head
--block`, whose end stops every process it started."""

from __future__ import annotations

import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

RAY = Path(sys.executable).parent / "ray"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def ray_head(cpus: int = 2, start_timeout: float = 90.0) -> Iterator[str]:
    """A head with ``cpus`` CPUs (that many tasks at a time); its Ray Client address."""
    client = free_port()
    cmd = [str(RAY), "start", "--head", "--block", "--node-ip-address=127.0.0.1"]
    cmd += [f"--port={free_port()}", f"--ray-client-server-port={client}", f"--num-cpus={cpus}"]
    cmd += ["--include-dashboard=false", "--disable-usage-stats"]
    cmd += ["--object-store-memory=100000000"]
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "head.log"
        with open(log, "w") as out:
            head = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT)
        try:
            deadline = time.monotonic() + start_timeout
            while "Ray runtime started" not in log.read_text():
                if head.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"the Ray head did not start:\n{log.read_text()}")
                time.sleep(0.2)
            yield f"ray://127.0.0.1:{client}"
        finally:
            head.terminate()
            head.wait(timeout=60)
