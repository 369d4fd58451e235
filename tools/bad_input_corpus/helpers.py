"""What the case modules share: copying a base input cheaply, and the names a message must hold."""

import os
import re
import shutil

from mutate import replace_file


class Spec:
    """One case, made lazily: build(case_dir) returns (moslam arguments, names), names being a
    list of groups of alternatives of which a clean error must hold one each (classify.py).
    cost: relative run time (1: a reader alone, 3: a short SLAM run). valid: the input is a
    good one (the base inputs), and anything but success is a failure."""

    def __init__(self, reader, name, build, cost=1, timeout=None, valid=False):
        self.reader, self.name, self.build = reader, name, build
        self.cost, self.timeout, self.valid = cost, timeout, valid


def clone(src, dst):
    """A copy of `src` (file or folder) whose files are hard links: mutations replace files
    (mutate.replace_file), so the base stays intact."""
    if os.path.isdir(src):
        shutil.copytree(src, dst, copy_function=os.link, dirs_exist_ok=True)
    else:
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        if os.path.lexists(dst):
            os.unlink(dst)
        os.link(src, dst)
    return dst


def read_lines(path):
    with open(path, encoding="utf-8", errors="surrogateescape") as f:
        return f.read().split("\n")


def write_lines(path, lines):
    replace_file(path, "\n".join(lines).encode("utf-8", "surrogateescape"))


def file_named(path):
    """A message names a file when it holds the path or, for a file in a folder given on the
    command line, the path from that folder (readers join folder and name)."""
    return [path, os.path.join(os.path.basename(os.path.dirname(path)), os.path.basename(path))]


def line_or_key(path, line=None, key=None):
    """One of: "<file>:<line>", the key."""
    alts = []
    if line is not None:
        alts += [f"{p}:{line}" for p in file_named(path)]
    if key:
        alts.append(key)
    return alts


def any_line_of(path):
    """"<file>:<some line number>", with the file as file_named gives it."""
    return [re.compile(re.escape(p) + r":\d+") for p in file_named(path)]


def damaged_line_names(path, lines, pick):
    """What a message about line `pick` of `path` (None: the whole file) must name: the file,
    and a line of it or the line's key ("P1" of KITTI's "P1: ...")."""
    names = [file_named(path)]
    if pick is not None:
        alts = any_line_of(path)
        first = lines[pick].split()[0] if lines[pick].split() else ""
        if first.endswith(":"):
            alts.append(first[:-1])
        names.append(alts)
    return names
