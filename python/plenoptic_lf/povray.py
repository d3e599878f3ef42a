# SPDX-License-Identifier: AGPL-3.0-or-later
"""Running POV-Ray: the one way this package's tools (plenoptic-targets, plenoptic-dataset, the
benchmark, the report's figures) and the tests' helper start the renderer.

    command = povray_command(povray, "scene.pov", "out.png", 320, 240, ["-D", "-P"])
    run = run_povray(command, cwd=folder, timeout=600)      # -> PovrayRun
    if not run.ok: ...                                      # run.output, run.returncode

The renderer runs in a session (process group) of its own, with no input; the time limit and an
interrupt reach it and every process it started: at the time limit the group is killed, on
Ctrl-C (KeyboardInterrupt in this process) it is sent SIGINT, given `interrupt_grace` seconds to
stop and then killed, and the KeyboardInterrupt goes on. Its output (stdout and stderr together,
or apart with separate=True) is captured, or appended to a log file. Any other command (a
wrapper such as valgrind, another tool) runs the same way.
"""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import time
from dataclasses import dataclass
from typing import IO, Sequence


@dataclass
class PovrayRun:
    """One finished run: the command, its exit status (negative: killed by that signal), its
    output as bytes (stdout and stderr together; apart too with separate=True; the log's whole
    content with a log file) and as text (.output, .stdout, .stderr: UTF-8, undecodable bytes
    replaced), wall-clock and CPU seconds (user + system of the process and its children), and
    whether the time limit killed it."""
    command: list[str]
    returncode: int
    seconds: float
    cpu_seconds: float
    timed_out: bool
    output_bytes: bytes
    stdout_bytes: bytes | None = None
    stderr_bytes: bytes | None = None

    @property
    def ok(self) -> bool:
        return self.returncode == 0 and not self.timed_out

    @property
    def output(self) -> str:
        return _decode(self.output_bytes)

    @property
    def stdout(self) -> str | None:
        return None if self.stdout_bytes is None else _decode(self.stdout_bytes)

    @property
    def stderr(self) -> str | None:
        return None if self.stderr_bytes is None else _decode(self.stderr_bytes)


def povray_command(povray: str, scene: str, output: str, width: int, height: int,
                   options: Sequence[str] = ()) -> list[str]:
    """[povray, +I<scene>, +O<output>, +W<width>, +H<height>, options...]."""
    return [povray, "+I" + scene, "+O" + output, "+W%d" % width, "+H%d" % height] + list(options)


def _stop(process: subprocess.Popen[bytes], grace: float) -> None:
    """SIGINT to the run's process group, then SIGKILL after `grace` seconds."""
    try:
        os.killpg(process.pid, signal.SIGINT)
        process.wait(timeout=grace)
    except (ProcessLookupError, subprocess.TimeoutExpired):
        try:
            os.killpg(process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        process.wait()


def _decode(data: bytes | None) -> str:
    return (data or b"").decode("utf-8", errors="replace")


def run_povray(command: Sequence[str], cwd: str | None = None, timeout: float | None = None,
               log: str | None = None, separate: bool = False, env: dict[str, str] | None = None,
               input_text: str | None = None, interrupt_grace: float = 30.0) -> PovrayRun:
    """Runs `command` (usually from povray_command) and waits for it; see the module's text.

    cwd: its working directory; timeout: seconds before its process group is killed (None: no
    limit); log: a file its output is appended to (its whole text is then PovrayRun.output);
    separate: capture stdout and stderr apart; env: its environment; input_text: given on its
    standard input (else it reads nothing). Output is decoded as UTF-8, undecodable bytes
    replaced. Raises OSError when the command cannot be started, KeyboardInterrupt after
    stopping it on Ctrl-C."""
    command = [str(c) for c in command]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.monotonic()
    log_file: IO[bytes] | None = open(log, "ab") if log is not None else None
    try:
        process = subprocess.Popen(
            command, cwd=cwd, env=env, start_new_session=True,
            stdin=subprocess.PIPE if input_text is not None else subprocess.DEVNULL,
            stdout=log_file if log_file is not None else subprocess.PIPE,
            stderr=subprocess.STDOUT if log_file is not None or not separate else subprocess.PIPE)
        timed_out = False
        data = input_text.encode("utf-8") if input_text is not None else None
        try:
            out, err = process.communicate(data, timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
            out, err = process.communicate()
            timed_out = True
        except KeyboardInterrupt:
            _stop(process, interrupt_grace)
            raise
    finally:
        if log_file is not None:
            log_file.close()
    seconds = time.monotonic() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if log is not None:
        with open(log, "rb") as f:
            return PovrayRun(command, process.returncode, seconds, cpu, timed_out, f.read())
    if separate:
        return PovrayRun(command, process.returncode, seconds, cpu, timed_out, (out or b"") + (err or b""),
                         out or b"", err or b"")
    return PovrayRun(command, process.returncode, seconds, cpu, timed_out, out or b"")
