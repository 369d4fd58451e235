"""Settings files (ORB-SLAM2 YAML): missing keys, typos, wrong types, absurd values and broken
YAML, read by `moslam dataset info --settings`; absurd camera values also through `moslam run`,
where they used to reach invariant checks (issue 31)."""

import os
import random

from helpers import Spec, clone, file_named, line_or_key, read_lines, write_lines
from mutate import BAD_SETTINGS_VALUES, replace_file

# Values for which a run must stop before tracking, naming the key (issue 31's aborts), or that
# the images contradict (a 640x480 camera for 320x240 images).
RUN_ABSURD = [("Camera.fx", "1e-300"), ("Camera.fx", "1e300"), ("Camera.fy", "1e300"),
              ("Camera.k1", "-1e6"), ("Camera.k3", "1e300"), ("Camera.p1", "0.9"),
              ("Camera.cx", "-5"), ("Camera.bf", "1e-9"), ("ORBextractor.nFeatures", "1"),
              ("ORBextractor.nLevels", "1"), ("ORBextractor.scaleFactor", "1.0001"),
              ("DepthMapFactor", "1e-30"), ("Camera.width", "640"), ("Camera.height", "480")]

STRUCTURAL = {
    "empty": b"",
    "header_only": b"%YAML:1.0\n",
    "binary": bytes(range(256)) * 4,
    "list_root": b"%YAML:1.0\n- a\n- b\n",
    "scalar_root": b"%YAML:1.0\n42\n",
    "unclosed_list": b"%YAML:1.0\nCamera.fx: [1, 2\n",
    "unclosed_map": b"%YAML:1.0\nCamera.fx: {a: 1\n",
    "unclosed_quote": b"%YAML:1.0\nCamera.fx: \"535\n",
    "tab_indent": b"%YAML:1.0\nCamera:\n\tfx: 535\n",
    "nul_byte": b"%YAML:1.0\nCamera.fx: 5\x0035\n",
    "deep_nesting": b"%YAML:1.0\n" + b"".join(b"  " * i + b"k%d:\n" % i for i in range(200)),
    "huge_key": b"%YAML:1.0\n" + b"k" * (1 << 20) + b": 1\n",
    "huge_value": b"%YAML:1.0\nCamera.fx: " + b"9" * (1 << 20) + b"\n",
    "binary_tag_hang": b"%YAML:1.0\nx: !!binary |\n   AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA\n",
    "binary_tag_spaces": b"%YAML:1.0\nx: !!binary |\n   ICAgICAgICAgICAgICAgICAgICAgICAg\n",
    "binary_tag_short": b"%YAML:1.0\nx: !!binary |\n  AAAA\n",
    "binary_tag_inline": b"%YAML:1.0\nx: !!binary AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA\n",
    "str_tag": b"%YAML:1.0\nCamera.fx: !!str 535\n",
    "custom_tag": b"%YAML:1.0\nCamera.fx: !foo 535\n",
    "anchor_alias": b"%YAML:1.0\na: &x 1\nb: *x\n",
    "matrix_bad_rows": b"%YAML:1.0\nm: !!opencv-matrix\n   rows: 9\n   cols: 1\n   dt: d\n"
                       b"   data: [1.0]\n",
    "matrix_bad_dt": b"%YAML:1.0\nm: !!opencv-matrix\n   rows: 1\n   cols: 1\n   dt: q\n"
                     b"   data: [1.0]\n",
}


def typo(rng, key):
    k = rng.randrange(len(key))
    kinds = [key[:k] + key[k + 1:], key[:k] + key[k] + key[k:], key.lower(), key + "s"]
    return rng.choice([t for t in kinds if t != key] or [key + "x"])


def keyed_lines(lines):
    return [(i, line.split(":", 1)[0].strip()) for i, line in enumerate(lines)
            if ":" in line and not line.startswith(("%", "#", " "))]


def value_spec(reader, name, base, dataset, sensor, i, key, value):
    def build(d):
        s = clone(base, os.path.join(d, "settings.yaml"))
        lines = read_lines(base)
        lines[i] = f"{key}: {value}"
        write_lines(s, lines)
        return (["dataset", "info", dataset, "--settings", s, "--sensor", sensor],
                [file_named(s), line_or_key(s, i + 1, key)])
    return Spec(reader, name, build)


def key_specs(rng, reader, tag, base, dataset, sensor, values_per_key):
    specs = []
    lines = read_lines(base)
    for i, key in keyed_lines(lines):
        for value in rng.sample(BAD_SETTINGS_VALUES, min(values_per_key, len(BAD_SETTINGS_VALUES))):
            safe = "".join(c if c.isalnum() else "_" for c in value)[:12] or "empty"
            specs.append(value_spec(reader, f"{tag}_{key}_{safe}", base, dataset, sensor, i, key,
                                    value))

        def missing(d, i=i, key=key):
            s = clone(base, os.path.join(d, "settings.yaml"))
            write_lines(s, lines[:i] + lines[i + 1:])
            return (["dataset", "info", dataset, "--settings", s, "--sensor", sensor],
                    [file_named(s)])
        specs.append(Spec(reader, f"{tag}_{key}_missing", missing))
        bad_key = typo(rng, key)

        def misspelt(d, i=i, key=key, bad_key=bad_key):
            s = clone(base, os.path.join(d, "settings.yaml"))
            copy = list(lines)
            copy[i] = copy[i].replace(key, bad_key, 1)
            write_lines(s, copy)
            return (["dataset", "info", dataset, "--settings", s, "--sensor", sensor],
                    [file_named(s), [bad_key, key]])
        specs.append(Spec(reader, f"{tag}_{key}_typo", misspelt))
    return specs


def structural_specs(reader, base, dataset):
    specs = []
    for name, data in STRUCTURAL.items():
        def build(d, data=data):
            s = os.path.join(d, "settings.yaml")
            replace_file(s, data)
            return ["dataset", "info", dataset, "--settings", s], [file_named(s)]
        specs.append(Spec(reader, f"yaml_{name}", build, timeout=30))
    text = open(base, "rb").read()
    variants = {"crlf": text.replace(b"\n", b"\r\n"), "bom": b"\xef\xbb\xbf" + text,
                "no_header": text.split(b"\n", 1)[1], "truncated_half": text[:len(text) // 2],
                "duplicate_key": text + b"Camera.fx: 600.0\n", "doubled": text + text}
    for name, data in variants.items():
        def build(d, data=data):
            s = os.path.join(d, "settings.yaml")
            replace_file(s, data)
            return ["dataset", "info", dataset, "--settings", s], [file_named(s)]
        specs.append(Spec(reader, f"yaml_{name}", build))

    def directory(d):
        return ["dataset", "info", dataset, "--settings", d], [file_named(d)]

    def absent(d):
        s = os.path.join(d, "none.yaml")
        return ["dataset", "info", dataset, "--settings", s], [file_named(s)]
    specs += [Spec(reader, "yaml_directory", directory), Spec(reader, "yaml_absent", absent)]
    return specs


def run_specs(inputs):
    """Absurd camera values through `moslam run`, with and without Camera.width/height."""
    base = os.path.join(inputs["tum"], "settings.yaml")
    lines = read_lines(base)
    specs = []
    for sized in (True, False):
        for key, value in RUN_ABSURD:
            def build(d, key=key, value=value, sized=sized):
                s = clone(base, os.path.join(d, "settings.yaml"))
                out = []
                for line in lines:
                    k = line.split(":", 1)[0]
                    if not sized and k in ("Camera.width", "Camera.height"):
                        continue
                    out.append(f"{key}: {value}" if k == key else line)
                write_lines(s, out)
                return (["run", "--dataset", "tum", inputs["tum"], "--settings", s, "--out",
                         os.path.join(d, "out"), "--quiet", "--no-loop-closing"],
                        [file_named(s), [key]])
            tag = "sized" if sized else "unsized"
            specs.append(Spec("settings-run", f"{tag}_{key}_{value}", build, cost=3))
    return specs


def specs(inputs, seed):
    rng = random.Random(seed)
    tum_settings = os.path.join(inputs["tum"], "settings.yaml")
    kitti_settings = os.path.join(inputs["kitti"], "settings.yaml")
    euroc = os.path.join(inputs["repo"], "configs", "EuRoC.yaml")
    out = key_specs(rng, "settings", "tum", tum_settings, inputs["tum"], "rgbd", 16)
    out += key_specs(rng, "settings", "kitti", kitti_settings, inputs["kitti"], "stereo", 5)
    out += key_specs(rng, "settings", "euroc", euroc, inputs["euroc"], "stereo", 2)
    out += structural_specs("settings", tum_settings, inputs["tum"])
    out += run_specs(inputs)
    return out
