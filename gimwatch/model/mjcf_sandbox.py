"""MuJoCo's compile of an MJCF file in a child process bounded in time and memory.

A 400-byte MJCF can expand without bound while MuJoCo reads it: three nested
``<replicate count="40">`` make 64,000 bodies and a parse that runs for minutes, a
``<flexcomp>`` can ask for millions of elements. The text budgets of
`gimwatch.model.mjcf_robot` cannot see that, and MuJoCo's compile ignores SIGINT and
SIGTERM while it runs. So the compile runs in a forked child:

* its address space is capped (``RLIMIT_AS``) at what it has at the fork plus
  `compile_memory_bytes` (``$GIMWATCH_MJCF_MEMORY_MB``, default 4096 MiB);
* the parent waits at most `compile_seconds` (``$GIMWATCH_MJCF_SECONDS``, default 60 s),
  then kills the child with SIGKILL (the one signal MuJoCo cannot defer) and refuses the file;
* the child hands the compiled model back as MuJoCo's binary MJB in a private temporary
  folder, removed before returning; a refusal comes back as MuJoCo's message.
"""

from __future__ import annotations

import os
import resource
import select
import shutil
import signal
import tempfile
import time
from collections.abc import Callable

from gimwatch.errors import URDFError

__all__ = [
    "DEFAULT_COMPILE_MEMORY_MB",
    "DEFAULT_COMPILE_SECONDS",
    "compile_in_child",
    "compile_memory_bytes",
    "compile_seconds",
]

#: The longest a compile may run (s); Menagerie's largest models compile in under 5 s.
DEFAULT_COMPILE_SECONDS = 60.0
#: The address space a compile may add to the process (MiB).
DEFAULT_COMPILE_MEMORY_MB = 4096
SECONDS_VARIABLE = "GIMWATCH_MJCF_SECONDS"
MEMORY_VARIABLE = "GIMWATCH_MJCF_MEMORY_MB"
_MIB = 1024 * 1024


def _positive_setting(variable: str, default: float) -> float:
    text = os.environ.get(variable, "").strip()
    if not text:
        return default
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise URDFError(f"${variable}", f"must be a positive number, got {text!r}")
    return value


def compile_seconds() -> float:
    """The compile's time bound in seconds (``$GIMWATCH_MJCF_SECONDS`` or 60)."""
    return _positive_setting(SECONDS_VARIABLE, DEFAULT_COMPILE_SECONDS)


def compile_memory_bytes() -> int:
    """The compile's memory bound in bytes (``$GIMWATCH_MJCF_MEMORY_MB`` MiB or 4096 MiB)."""
    return int(_positive_setting(MEMORY_VARIABLE, DEFAULT_COMPILE_MEMORY_MB) * _MIB)


def _address_space_now() -> int:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


def _child(compile_model: Callable, mjb_path: str, write_fd: int, memory: int) -> None:
    """In the forked child: compile, save MJB, report b"ok" or the error text; never return."""
    status = 1
    try:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        limit = _address_space_now() + memory
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
        import mujoco

        try:
            mujoco.mj_saveModel(compile_model(), mjb_path)
            message, status = b"ok", 0
        except MemoryError:
            message = b"memory"
        except URDFError as exc:  # gimwatch's own refusal, passed on as it is
            message = b"refused:" + exc.problem.encode("utf-8", "replace")
        except Exception as exc:  # the parent turns the text into one URDFError line
            message = b"error:" + (str(exc) or type(exc).__name__).encode("utf-8", "replace")
        os.write(write_fd, message[:65536])
    finally:
        os._exit(status)


def compile_in_child(
    compile_model: Callable,
    source: str,
    describe: Callable[[str], str],
    *,
    seconds: float | None = None,
    memory_bytes: int | None = None,
):
    """``compile_model()`` (an ``MjModel``) run in a child bounded in time and memory.

    Args:
        compile_model: Compiles and returns the model (called in the child only).
        source: The file, for messages.
        describe: Turns the child's error text into the one-line reason.
        seconds: The time bound (default `compile_seconds`).
        memory_bytes: The added address space allowed (default `compile_memory_bytes`).

    Raises:
        URDFError: The compile failed (MuJoCo's reason), ran past the time bound or the
            memory bound; the child is killed and nothing is left on disk.
    """
    import mujoco

    seconds = compile_seconds() if seconds is None else seconds
    memory = compile_memory_bytes() if memory_bytes is None else memory_bytes
    folder = tempfile.mkdtemp(prefix="gimwatch-mjcf-")
    mjb_path = os.path.join(folder, "model.mjb")
    read_fd, write_fd = os.pipe()
    pid = -1
    try:
        pid = os.fork()
        if pid == 0:
            os.close(read_fd)
            _child(compile_model, mjb_path, write_fd, memory)
        os.close(write_fd)
        write_fd = -1
        message = _read_until(read_fd, time.monotonic() + seconds)
        if message is None:
            raise URDFError(
                source,
                f"MuJoCo's compile ran past {seconds:g} s (an expanding <replicate> or "
                f"<flexcomp>?); stopped (set ${SECONDS_VARIABLE} to allow more)",
            )
        _, status = os.waitpid(pid, 0)
        pid = -1
        if message == b"ok" and os.WIFEXITED(status) and os.WEXITSTATUS(status) == 0:
            return mujoco.MjModel.from_binary_path(mjb_path)
        if message.startswith(b"refused:"):
            raise URDFError(source, message.removeprefix(b"refused:").decode("utf-8", "replace"))
        if message.startswith(b"error:"):
            text = message.removeprefix(b"error:").decode("utf-8", "replace")
            # under RLIMIT_AS, a failed allocation reaches Python as pybind11's "unknown exception"
            memory_words = ("allocat", "bad_alloc", "out of memory", "unknown exception")
            if not any(word in text.lower() for word in memory_words):
                raise URDFError(source, f"MuJoCo refuses this MJCF: {describe(text)}")
        elif message != b"memory" and os.WIFSIGNALED(status):
            name = signal.Signals(os.WTERMSIG(status)).name
            raise URDFError(
                source,
                f"MuJoCo's compile died ({name}) within a memory bound of {memory // _MIB} MiB "
                f"(set ${MEMORY_VARIABLE} to allow more)",
            )
        raise URDFError(
            source,
            f"MuJoCo's compile failed within a memory bound of {memory // _MIB} MiB (an "
            f"expanding <replicate> or <flexcomp>?; set ${MEMORY_VARIABLE} to allow more)",
        )
    finally:
        if pid > 0:  # timed out or interrupted: MuJoCo defers SIGTERM, not SIGKILL
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
        os.close(read_fd)
        if write_fd >= 0:
            os.close(write_fd)
        shutil.rmtree(folder, ignore_errors=True)


def _read_until(fd: int, deadline: float) -> bytes | None:
    """All the child writes before it closes the pipe, or None past ``deadline``."""
    chunks: list[bytes] = []
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        ready, _, _ = select.select([fd], [], [], min(left, 0.5))
        if ready:
            chunk = os.read(fd, 65536)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)
