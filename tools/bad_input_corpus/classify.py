"""Runs one command with a timeout and sorts the outcome into a class.

Classes: "clean error" (non-zero exit, the message names what it must), "success" (exit 0),
and the failures: "crash" (a signal, an abort, a failed CHECK, moslam's "unexpected error" exit 3),
"hang" (the timeout), "nameless error" (non-zero exit, a message that names neither the file nor
the key), "huge message" (stderr beyond MAX_STDERR: a message that quotes a whole file) and, for
the valid base inputs the corpus also runs, "valid input refused" (anything but success).
"""

import os
import re
import signal
import subprocess

FAILURES = ("crash", "hang", "nameless error", "huge message", "valid input refused")
CLASSES = ("clean error", "success") + FAILURES
MAX_STDERR = 64 * 1024
UNEXPECTED_EXIT = 3  # apps/moslam/main.cc: an exception that is not an InputError
CRASH_PATTERNS = re.compile(
    r"check failed|unexpected error|terminate called|Segmentation fault|core dumped|"
    r"AddressSanitizer|UndefinedBehaviorSanitizer|runtime error:|Assertion .* failed", re.I)


def run_command(argv, cwd, timeout, env):
    """(returncode or None on timeout, stderr text). The command gets its own process group so
    that a timeout ends it and every child it started."""
    proc = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, start_new_session=True)
    try:
        _, err = proc.communicate(timeout=timeout)
        return proc.returncode, err.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        _, err = proc.communicate()
        return None, err.decode("utf-8", "replace")


def names_everything(stderr, names):
    """Whether stderr holds one alternative of every group in `names` (a list of lists); an
    alternative is a string or a compiled regular expression."""

    def found(alt):
        return alt.search(stderr) is not None if isinstance(alt, re.Pattern) else alt in stderr

    return all(any(found(alt) for alt in group) for group in names)


def classify(returncode, stderr, names):
    if returncode is None:
        return "hang"
    if returncode < 0 or returncode >= 128 or returncode == UNEXPECTED_EXIT:
        return "crash"
    if CRASH_PATTERNS.search(stderr):
        return "crash"
    if len(stderr) > MAX_STDERR:
        return "huge message"
    if returncode == 0:
        return "success"
    return "clean error" if names_everything(stderr, names) else "nameless error"
