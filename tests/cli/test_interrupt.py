"""Ctrl-C stops every command at once: exit status 130, one line ("interrupted"), no traceback, no
file half-written (jaxslosh/run/guard.py stop_on_signals, installed by jaxslosh/entry.py). It once
printed a 40-line traceback during JAX's import, and later landed in a callback of XLA's garbage
collection, where Python ignores it: the stability command went on, wrote its figure and exited 0."""
import os
import signal
import subprocess
import sys
import textwrap
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ENV = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))


def interrupt_after(args, seconds, cwd):
    p = subprocess.Popen([sys.executable, "-m", "jaxslosh", *args], cwd=cwd, env=ENV,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(seconds)
    ran_on = p.poll() is None
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=120)
    return ran_on, p.returncode, out, err


def test_stability_stops_on_ctrl_c(tmp_path):
    """At 1 s the command imports (the scene checked, JAX loading); at 2.5 s and 4 s it computes the
    GZ curves (about 6 s in all on an idle 2-core machine: a later signal can land in the
    interpreter's own teardown, after the command's work, which this test does not judge)."""
    scene = os.path.join(ROOT, "scenes", "paper_ship_stability.toml")
    stopped = 0
    for seconds in (1.0, 2.5, 4.0):
        fig = tmp_path / f"gz{seconds}.png"
        ran_on, code, out, err = interrupt_after(["stability", scene, "-o", str(fig)], seconds, tmp_path)
        if not ran_on:              # done before the signal (a fast machine): nothing to see
            continue
        stopped += 1
        assert code == 130, (seconds, code, err[-2000:])
        assert err.strip().splitlines() == ["interrupted"], (seconds, err[-2000:])
        assert "Traceback" not in out + err
        assert not fig.exists()
        assert list(tmp_path.iterdir()) == []           # nothing else either
    assert stopped >= 2


FINISHING = textwrap.dedent("""
    import os, signal, sys, time
    from jaxslosh.run.guard import finishing, stop_on_signals
    stop_on_signals()
    with finishing():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.3)                         # the handler has run: the block holds it off
        with open(sys.argv[1], "w") as f:
            f.write("whole")
    print("not reached")
""")


def test_a_file_being_written_is_finished_first(tmp_path):
    out = tmp_path / "file.txt"
    p = subprocess.run([sys.executable, "-c", FINISHING, str(out)], env=ENV, capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 130
    assert p.stderr.strip() == "interrupted" and p.stdout == ""
    assert out.read_text() == "whole"


ENDS_AT_ITS_END = textwrap.dedent("""
    import atexit, sys
    atexit.register(lambda: open(sys.argv[1], "w").write("teardown"))
    sys.argv = ["jaxslosh", "check", sys.argv[2]]
    from jaxslosh.entry import main
    main()
    print("not reached")
""")


def test_the_program_ends_with_its_command_not_in_the_teardown(tmp_path):
    """A Ctrl-C in the interpreter's teardown (after the command's work, Python having given SIGINT
    back its default action) once killed the process silently with status -2: the program now ends
    with its command's status (jaxslosh/entry.py), the teardown's exit handlers never reached."""
    mark = tmp_path / "teardown.txt"
    scene = os.path.join(ROOT, "scenes", "vessel_only.toml")
    p = subprocess.run([sys.executable, "-c", ENDS_AT_ITS_END, str(mark), scene], cwd=tmp_path, env=ENV,
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr[-2000:]
    assert "not reached" not in p.stdout and p.stdout.strip()      # the check's own report, whole
    assert not mark.exists()
