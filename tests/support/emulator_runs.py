"""`python -m emulator` runs for the tests (and `python -m reference`, `python -m sdcard_image`
runs), each in a process of its own, without paying for the interpreter's start and the
project's imports each time (about 0.2 s a run of the board model, some 270 runs a suite; 0.3 s
a run of the other two).

A server process (`python tests/support/emulator_runs.py`, one per test process, started at the first
run) imports the board model, the reference renderer and the card tool once and forks a child
for each run the tests ask for. The child sets the asking test's working folder and environment,
writes its standard output and error to files the test names, runs the package's `__main__` as
`python -m <package>` would, and exits with its status; the server reports the status back. What
differs from a run started from the shell is only what was imported before the command line was
read.

The tests that check the command as a user types it (test_readme_commands.py, the `--help` and
bad-option tests) still start `python -m emulator` themselves.

Protocol, one JSON object a line: the test sends {"module", "args", "cwd", "env", "stdout",
"stderr"}; the server answers {"pid"} once the child exists and {"status"} once it has ended (the
exit status, or minus the signal that ended it, as subprocess reports it).
"""
from __future__ import annotations

import atexit
import gc
import json
import os
import runpy
import select
import signal
import subprocess
import sys
import tempfile
import threading
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MODULES = ("emulator", "reference", "sdcard_image")    # the packages whose `python -m` runs are served


# --- the server ----------------------------------------------------------------------------

def _run_child(request: dict) -> None:
    """In the forked child: becomes the `python -m <module>` run `request` describes; never returns."""
    status = 1
    try:
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        nothing = os.open(os.devnull, os.O_RDONLY)
        out = os.open(request["stdout"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        err = os.open(request["stderr"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        for source, target in ((nothing, 0), (out, 1), (err, 2)):
            os.dup2(source, target)
            os.close(source)
        # the streams a fresh interpreter would make for files: block-buffered output, line-buffered errors
        sys.stdin = open(0, "r", closefd=False)
        sys.stdout = open(1, "w", closefd=False)
        sys.stderr = open(2, "w", buffering=1, errors="backslashreplace", closefd=False)
        module = request["module"]
        sys.argv = [str(ROOT / module / "__main__.py"), *request["args"]]
        try:
            runpy.run_module(module, run_name="__main__", alter_sys=True)
            status = 0
        except SystemExit as end:
            if end.code is None:
                status = 0
            elif isinstance(end.code, int):
                status = end.code
            else:
                print(end.code, file=sys.stderr)
                status = 1
        except BaseException:
            traceback.print_exc()
            status = 1
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(status & 0xFF)


def serve() -> None:
    """Reads requests from standard input until it ends, answering on standard output (anything
    else the server itself prints goes to standard error)."""
    answers = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    import emulator.frontends.cli  # noqa: F401  (what every run imports, once, before the forks)
    import emulator.frontends.console_watch, emulator.frontends.golden, emulator.frontends.trace, emulator.frontends.uart_input, emulator.frontends.vcd  # noqa: F401,E401
    import PIL.Image, PIL.PngImagePlugin  # noqa: F401,E401
    import reference.cli, sdcard_image.cli  # noqa: F401,E401
    from emulator.board import Board
    firmware = ROOT / "build" / "firmware.elf"
    try:
        # what a board learns of the firmware most runs use (its symbols, CSR sites, poll loops,
        # cycle table) and the power-on SRAM pattern are kept in the process, for every fork; a
        # firmware missing or being rebuilt just now leaves that to each run
        Board(str(firmware)).close()
    except Exception:  # noqa: BLE001
        pass
    # What the server holds now is never freed: frozen, a child's collections do not scan it. A
    # collection writes to every object it scans, so each would copy the pages of the whole
    # inherited heap (about 30 ms of a 150 ms run).
    gc.freeze()
    for line in sys.stdin:
        request = json.loads(line)
        pid = os.fork()
        if pid == 0:
            answers.close()
            _run_child(request)
        answers.write(json.dumps({"pid": pid}) + "\n")
        answers.flush()
        _, wait_status = os.waitpid(pid, 0)
        answers.write(json.dumps({"status": os.waitstatus_to_exitcode(wait_status)}) + "\n")
        answers.flush()


# --- the tests' side -----------------------------------------------------------------------

class _Server:
    """A server of this test process (started when a run finds none idle, ended with the process)."""

    def __init__(self) -> None:
        # one BLAS thread: the server forks, and the board model does no linear algebra
        environment = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        self.process = subprocess.Popen([sys.executable, __file__], cwd=ROOT, env=environment,
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0)
        self._received = b""     # answers read from the pipe and not yet taken
        atexit.register(self.close)

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.stdin.close()
            self.process.wait()

    def _answer(self, timeout: float | None) -> dict | None:
        """The server's next answer, or None when `timeout` seconds pass first."""
        pipe = self.process.stdout.fileno()
        deadline = None if timeout is None else time.monotonic() + timeout
        while b"\n" not in self._received:
            if deadline is not None:
                ready, _, _ = select.select([pipe], [], [], max(0.0, deadline - time.monotonic()))
                if not ready:
                    return None
            chunk = os.read(pipe, 4096)
            if not chunk:
                raise RuntimeError(f"the emulator run server ended (status {self.process.poll()})")
            self._received += chunk
        line, self._received = self._received.split(b"\n", 1)
        return json.loads(line)

    def run(self, module: str, args: list[str], timeout: float, cwd: Path, text: bool) -> subprocess.CompletedProcess:
        command = [sys.executable, "-m", module, *args]
        with tempfile.TemporaryDirectory(prefix=f"{module}-run-") as folder:
            out, err = Path(folder) / "stdout", Path(folder) / "stderr"
            request = {"module": module, "args": list(args), "cwd": str(cwd), "env": dict(os.environ),
                       "stdout": str(out), "stderr": str(err)}
            self.process.stdin.write(json.dumps(request).encode() + b"\n")
            pid = self._answer(None)["pid"]
            answer = self._answer(timeout)
            if answer is None:
                os.kill(pid, signal.SIGKILL)
                self._answer(None)
                raise subprocess.TimeoutExpired(command, timeout, out.read_bytes(), err.read_bytes())
            if not text:
                return subprocess.CompletedProcess(command, answer["status"], out.read_bytes(), err.read_bytes())
            return subprocess.CompletedProcess(command, answer["status"],
                                               out.read_text(errors="replace"), err.read_text(errors="replace"))


_idle_servers: list[_Server] = []
_servers_lock = threading.Lock()


def run_module(module: str, *args: str | Path, timeout: float = 600, cwd: Path = ROOT,
               text: bool = True) -> subprocess.CompletedProcess:
    """Runs `python -m module args` (module one of MODULES) in a process of its own (see the
    module's docstring), from `cwd` (the project's root unless given), with standard input empty;
    its output as subprocess.run(..., capture_output=True, text=text) gives it. Runs asked for at
    once (from threads) each get a server of their own."""
    if module not in MODULES:
        raise ValueError(f"{module}: not one of the packages the run server has imported ({', '.join(MODULES)})")
    with _servers_lock:
        server = _idle_servers.pop() if _idle_servers else None
    if server is None or server.process.poll() is not None:
        server = _Server()
    try:
        return server.run(module, [str(arg) for arg in args], timeout, Path(cwd), text)
    finally:
        with _servers_lock:
            _idle_servers.append(server)


def run_emulator(*args: str, timeout: float = 600) -> subprocess.CompletedProcess:
    """`python -m emulator args` from the project's root (run_module)."""
    return run_module("emulator", *args, timeout=timeout)


if __name__ == "__main__":
    serve()
