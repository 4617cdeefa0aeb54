"""evalsuite.cli: the console entry point ``run`` ends the process quickly once a command has finished, with
the command's exit status, after the exit handlers ran and the output was flushed; it keeps the normal
shutdown while another thread still runs."""
from __future__ import annotations

import subprocess
import sys
import textwrap

from evalsuite._version import __version__


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code), *args], capture_output=True, text=True,
                          timeout=120)


def test_exit_status_of_each_outcome_and_output_flushed():
    ok = subprocess.run([sys.executable, "-m", "evalsuite", "--version"], capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0 and __version__ in ok.stdout
    usage = subprocess.run([sys.executable, "-m", "evalsuite", "no-such-command"], capture_output=True, text=True,
                           timeout=120)
    assert usage.returncode == 2 and "No such command" in usage.stderr
    bad = subprocess.run([sys.executable, "-m", "evalsuite", "info", __file__], capture_output=True, text=True,
                         timeout=120)
    assert bad.returncode == 1 and "Error" in bad.stderr


def test_exit_handlers_run_before_the_quick_exit(tmp_path):
    marker = tmp_path / "handler-ran"
    proc = _python("""
        import atexit, pathlib, sys
        from evalsuite.cli import run
        path = pathlib.Path(sys.argv[1])
        atexit.register(lambda: path.write_text("yes"))
        sys.stdout.write("unflushed output ")   # left in the buffer: the quick exit must flush it
        sys.argv = ["evalsuite", "--version"]
        run()
        """, str(marker))
    assert proc.returncode == 0
    assert marker.read_text() == "yes"
    assert proc.stdout.startswith("unflushed output ") and __version__ in proc.stdout


def test_a_running_thread_keeps_the_normal_shutdown(tmp_path):
    marker = tmp_path / "thread-done"
    proc = _python("""
        import pathlib, sys, threading, time
        from evalsuite.cli import run
        path = pathlib.Path(sys.argv[1])
        threading.Thread(target=lambda: (time.sleep(0.5), path.write_text("done"))).start()
        sys.argv = ["evalsuite", "--version"]
        run()
        """, str(marker))
    assert proc.returncode == 0
    assert marker.read_text() == "done"     # the interpreter waited for the thread, as without run()


def test_gl_contexts_are_left_to_the_os_on_the_quick_exit(tmp_path):
    """renderers._gl.free_contexts (pyrender's delete: a full garbage collection) is not run before the quick
    exit; the other exit handlers are."""
    freed, other = tmp_path / "freed", tmp_path / "other"
    proc = _python("""
        import atexit, pathlib, sys
        import renderers._gl as gl
        freed, other = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
        def free_contexts():
            freed.write_text("yes")
        gl.free_contexts = free_contexts           # as registered when a context was made
        atexit.register(free_contexts)
        atexit.register(lambda: other.write_text("yes"))
        from evalsuite.cli import run
        sys.argv = ["evalsuite", "--version"]
        run()
        """, str(freed), str(other))
    assert proc.returncode == 0, proc.stderr
    assert other.read_text() == "yes" and not freed.exists()
