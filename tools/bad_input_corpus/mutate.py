"""Mutations of text and binary files, seeded: every function takes a random.Random."""

import os

# Values that are wrong for a number field in every reader: not numbers, not finite, absurd.
BAD_NUMBERS = ["nan", "NaN", "-nan", "inf", "-inf", ".nan", ".inf", "1e400", "-1e400", "1e300",
               "-1e300", "1e-300", "0x1f", "017", "abc", "1,5", "1..2", "--1", "", "\"1\"",
               "[1, 2]", "2147483648", "-2147483649", "0", "-1", "1e6"]

# Values for a settings key: wrong types and absurd numbers.
BAD_SETTINGS_VALUES = ["abc", "\"12\"", "[1, 2]", "{a: 1}", "true", "", "nan", ".inf", "-.inf",
                       "1e300", "-1e300", "1e-300", "0", "-1", "0x217", "017", "2147483648",
                       "1e6", "-1e6", "0.5", "~", "!!binary |\n   AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"]


def replace_file(path, data):
    """Writes `data` (str or bytes) to `path` without touching a hard-linked original."""
    if os.path.lexists(path):
        os.unlink(path)
    mode = "wb" if isinstance(data, (bytes, bytearray)) else "w"
    with open(path, mode) as f:
        f.write(data)


def substitute_path(path, data):
    """Replaces the file at `path`: by `data` (str or bytes), by a directory ("dir"), or by
    nothing (None: the file is gone)."""
    os.unlink(path)
    if data == "dir":
        os.makedirs(path)
    elif data is not None:
        replace_file(path, data)


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def data_line_indices(lines):
    """Indices of the lines that carry data (not blank, not comments)."""
    return [i for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]


def line_mutations(rng, lines, field_sep=" ", max_fields=4):
    """(name, new lines, damaged line index) triples that break a line-oriented list: each a
    different kind of damage, most of them to one line picked at random."""
    idx = data_line_indices(lines)
    out = []
    if not idx:
        return out
    pick = idx[rng.randrange(len(idx))]
    first, last = idx[0], idx[-1]
    fields = lines[pick].split(field_sep)

    def with_line(i, text):
        copy = list(lines)
        copy[i] = text
        return copy

    def with_field(i, k, value):
        f = lines[i].split(field_sep)
        f[k % len(f)] = value
        return with_line(i, field_sep.join(f))

    for k in sorted(rng.sample(range(len(fields)), min(max_fields, len(fields)))):
        for bad in rng.sample(BAD_NUMBERS, 3):
            out.append((f"field{k}_{bad or 'empty'}", with_field(pick, k, bad), pick))
    others = [lines[i] for i in range(len(lines)) if i not in idx]
    out += [
        ("drop_field", with_line(pick, field_sep.join(fields[:-1])), pick),
        ("extra_field", with_line(pick, lines[pick] + field_sep + "7"), pick),
        ("only_first_field", with_line(pick, fields[0]), pick),
        ("swap_lines", _swapped(lines, first, last), first),
        ("duplicate_line", lines[:pick + 1] + [lines[pick]] + lines[pick + 1:], pick + 1),
        ("reversed", others + [lines[i] for i in reversed(idx)], None),
        ("delete_line", lines[:pick] + lines[pick + 1:], None),
        ("truncate_mid_line", lines[:pick] + [lines[pick][:len(lines[pick]) // 2]], pick),
        ("tabs", [line.replace(field_sep, "\t") for line in lines], None),
        ("garbage_line", with_line(pick, "\x00\x01\xff garbage \x7f"), pick),
        ("huge_line", with_line(pick, lines[pick] + " " + "9" * 300000), pick),
        ("no_data", others, None),
        ("one_line", [lines[first]], None),
    ]
    return out


def _swapped(lines, a, b):
    copy = list(lines)
    copy[a], copy[b] = copy[b], copy[a]
    return copy


def byte_mutations(rng, data):
    """(name, bytes) pairs that damage a binary file: truncations, flips, empties, garbage."""
    n = len(data)
    out = [("empty", b""), ("one_byte", data[:1]), ("garbage", bytes(rng.randrange(256)
                                                                     for _ in range(512)))]
    for frac in (0.1, 0.5, 0.9):
        cut = max(1, int(n * frac))
        out.append((f"truncated_{int(frac * 100)}pct", data[:cut]))
    for k in (1, 16):
        b = bytearray(data)
        for _ in range(k):
            if n:
                b[rng.randrange(n)] ^= 1 << rng.randrange(8)
        out.append((f"flip{k}", bytes(b)))
    out.append(("text", b"this is not the file you are looking for\n"))
    out.append(("doubled", data + data))
    return out
