"""Mask folders (`moslam run --mask-source files`, `moslam features --mask`), model cards and
model files (`moslam segment`), vocabularies (`moslam vocab info|convert`, `moslam run
--vocabulary`), CRF inputs (`moslam crf`) and map files (`moslam run --load-map`)."""

import os
import random

import cv2
import numpy as np

from cases_datasets import image_variants, run_args
from helpers import (Spec, clone, damaged_line_names, file_named, line_or_key, read_lines,
                     write_lines)
from mutate import byte_mutations, line_mutations, read_bytes, replace_file, substitute_path

CARD_VALUES = ["abc", "-1", "0", "1e9", "nan", "[1, 2]", "", "\"x\"", "{a: 1}", "1e-300"]


def mask_specs(rng, inputs):
    tum, masks = inputs["tum"], inputs["masks"]
    name = sorted(os.listdir(masks))[2]
    specs = []
    variants = image_variants(rng, os.path.join(masks, name))
    variants += [("missing", None), ("directory", "dir")]
    for variant, data in variants:
        def build(d, data=data):
            m = clone(masks, os.path.join(d, "masks"))
            path = os.path.join(m, name)
            substitute_path(path, data)
            s = os.path.join(tum, "settings.yaml")
            return run_args("tum", tum, s, d, ["--mask-source", "files", m]), [file_named(path)]
        specs.append(Spec("masks", f"run_{variant}", build, cost=3))

        def features(d, data=data):
            path = os.path.join(d, "mask.png")
            if data == "dir":
                os.makedirs(path)
            elif data is not None:
                replace_file(path, data)
            image = os.path.join(tum, "rgb", name)
            return (["features", image, "--mask", path, "--out", os.path.join(d, "o.png")],
                    [file_named(path) + ["mask"]])
        specs.append(Spec("masks", f"features_{variant}", features))

    def empty(d):
        m = os.path.join(d, "masks")
        os.makedirs(m)
        s = os.path.join(tum, "settings.yaml")
        return run_args("tum", tum, s, d, ["--mask-source", "files", m]), [[m]]
    for dilate in ("5000", "-3"):
        def dilated(d, dilate=dilate):
            s = os.path.join(tum, "settings.yaml")
            return (run_args("tum", tum, s, d, ["--mask-source", "synth-gt", "--mask-dilate",
                                                dilate]), [["--mask-dilate", "dilate"]])
        specs.append(Spec("masks", f"run_dilate_{dilate}", dilated, cost=3))
    specs.append(Spec("masks", "run_empty_folder", empty, cost=3))
    return specs


def card_base(inputs, d):
    """The torch card with its model named by an absolute path, written into d."""
    repo = inputs["repo"]
    lines = read_lines(os.path.join(repo, "configs", "models", "weak_synth_person.yaml"))
    model = os.path.join(repo, "data", "models", "weak_synth_person.mnet")
    lines = [f"model: {model}" if line.startswith("model:") else line for line in lines]
    card = os.path.join(d, "card.yaml")
    write_lines(card, lines)
    return card, lines


def segment_args(inputs, card, d, extra=()):
    images = os.path.join(inputs["tum"], "rgb")
    return (["segment", "--images", images, "--model-card", card, "--frames", "0:2", "--out",
             os.path.join(d, "out")] + list(extra))


def card_specs(rng, inputs):
    specs = []
    template, lines = card_base(inputs, inputs["base"])
    keyed = [(i, line.split(":", 1)[0]) for i, line in enumerate(lines)
             if ":" in line and not line.startswith(("%", "#"))]
    for i, raw_key in keyed:
        key = raw_key.strip()
        for value in rng.sample(CARD_VALUES, 5):
            def build(d, i=i, raw_key=raw_key, key=key, value=value):
                card, lines = card_base(inputs, d)
                copy = list(lines)
                copy[i] = f"{raw_key}: {value}"
                write_lines(card, copy)
                return segment_args(inputs, card, d), [file_named(card),
                                                      line_or_key(card, i + 1, key)]
            safe = "".join(c if c.isalnum() else "_" for c in value) or "empty"
            specs.append(Spec("card", f"{key}_{safe}", build, cost=2))
    sizes = [("1", "1"), ("7", "5"), ("8000", "6000"), ("65536", "2")]
    for w, h in sizes:
        def sized(d, w=w, h=h):
            card, lines = card_base(inputs, d)
            copy = [f"input_width: {w}" if line.startswith("input_width:") else
                    f"input_height: {h}" if line.startswith("input_height:") else line
                    for line in lines]
            write_lines(card, copy)
            return segment_args(inputs, card, d), [file_named(card), ["input_width",
                                                                      "input_height"]]
        specs.append(Spec("card", f"input_{w}x{h}", sized, cost=3, timeout=90))
    for name, text in [("empty", ""), ("list_root", "%YAML:1.0\n- a\n"), ("no_type",
                       "%YAML:1.0\nname: x\n"), ("bad_yaml", "%YAML:1.0\ntype: [torch\n"),
                       ("unknown_type", "%YAML:1.0\ntype: magic\n"), ("binary", "\x00\x01\x02")]:
        def build(d, text=text):
            card = os.path.join(d, "card.yaml")
            replace_file(card, text)
            return segment_args(inputs, card, d), [file_named(card)]
        specs.append(Spec("card", f"yaml_{name}", build))

    def valid(d):
        card, _ = card_base(inputs, d)
        return segment_args(inputs, card, d), []
    specs.append(Spec("card", "valid", valid, cost=2, valid=True))
    return specs


def model_specs(rng, inputs):
    repo = inputs["repo"]
    model = os.path.join(repo, "data", "models", "weak_synth_person.mnet")
    specs = []
    for name, data in byte_mutations(rng, read_bytes(model)):
        def build(d, data=data):
            card, lines = card_base(inputs, d)
            path = os.path.join(d, "model.mnet")
            replace_file(path, data)
            write_lines(card, [f"model: {path}" if line.startswith("model:") else line
                               for line in lines])
            return segment_args(inputs, card, d), [file_named(path)]
        specs.append(Spec("model", f"mnet_{name}", build, cost=2))
    shared = inputs["shared"]
    if shared:
        for card_name, rel in [("deeplabv3_mnv2_voc", "models/deeplabv3_mnv2_voc/"
                                "deeplabv3_mnv2_voc.onnx"),
                               ("yolo_fastest_coco", "models/yolo_fastest_coco/"
                                "yolo-fastest-1.1-xl.weights")]:
            original = os.path.join(shared, rel)
            if not os.path.isfile(original):
                continue
            for name, data in byte_mutations(rng, read_bytes(original))[:6]:
                def build(d, data=data, card_name=card_name, original=original):
                    path = os.path.join(d, os.path.basename(original))
                    replace_file(path, data)
                    lines = read_lines(os.path.join(repo, "configs", "models", card_name + ".yaml"))
                    lines = [f"model: {path}" if line.startswith("model:") else line
                             for line in lines]
                    lines = [line.replace("config: models/", f"config: {shared}/models/")
                             for line in lines]
                    card = os.path.join(d, "card.yaml")
                    write_lines(card, lines)
                    return segment_args(inputs, card, d), [file_named(path)]
                specs.append(Spec("model", f"{card_name}_{name}", build, cost=3))
    return specs


def vocab_specs(rng, inputs):
    text, binary = inputs["vocab_text"], inputs["vocab_binary"]
    specs = []
    lines = read_lines(text)
    for name, mutated, pick in line_mutations(rng, lines, " ", max_fields=6):
        def build(d, mutated=mutated, pick=pick):
            path = os.path.join(d, "voc.txt")
            write_lines(path, mutated)
            return ["vocab", "info", path], damaged_line_names(path, lines, pick)
        specs.append(Spec("vocab", f"text_{name}", build))
    for name, header in [("k0", "0 2 0 0"), ("huge_k", "100000 9 0 0"), ("scoring", "3 2 5 0"),
                         ("weighting", "3 2 0 3"), ("negative", "-3 2 0 0"), ("short", "3 2")]:
        def build(d, header=header):
            path = os.path.join(d, "voc.txt")
            write_lines(path, [header] + lines[1:])
            return ["vocab", "info", path], [file_named(path)]
        specs.append(Spec("vocab", f"header_{name}", build))
    data = read_bytes(binary)
    mutations = byte_mutations(rng, data)
    mutations += [(f"cut_{n}", data[:n]) for n in range(4, min(len(data), 200), 9)]
    for name, mutated in mutations:
        def build(d, mutated=mutated):
            path = os.path.join(d, "voc.mvoc")
            replace_file(path, mutated)
            return ["vocab", "info", path], [file_named(path)]
        specs.append(Spec("vocab", f"binary_{name}", build))
    for name, mutated in mutations[:4]:
        def run(d, mutated=mutated):
            path = os.path.join(d, "voc.mvoc")
            replace_file(path, mutated)
            tum = inputs["tum"]
            return (run_args("tum", tum, os.path.join(tum, "settings.yaml"), d,
                             ["--vocabulary", path]), [file_named(path)])
        specs.append(Spec("vocab", f"run_{name}", run, cost=3))

    def directory(d):
        return ["vocab", "info", d], [file_named(d)]

    def absent(d):
        return ["vocab", "info", os.path.join(d, "none.mvoc")], [[os.path.join(d, "none.mvoc")]]

    def run_directory(d):
        tum = inputs["tum"]
        return (run_args("tum", tum, os.path.join(tum, "settings.yaml"), d, ["--vocabulary", d]),
                [file_named(d)])
    specs += [Spec("vocab", "directory", directory), Spec("vocab", "absent", absent),
              Spec("vocab", "run_directory", run_directory, cost=3)]

    def valid(d):
        return ["vocab", "info", clone(binary, os.path.join(d, "voc.mvoc"))], []
    specs.append(Spec("vocab", "valid", valid, valid=True))
    return specs


def crf_specs(rng, inputs):
    image = os.path.join(inputs["tum"], "rgb", sorted(os.listdir(os.path.join(inputs["tum"],
                                                                             "rgb")))[0])
    h, w = cv2.imread(image).shape[:2]
    arrays = {"wrong_size": np.full((h // 2, w, 2), 0.5, np.float32),
              "one_label": np.ones((h, w, 1), np.float32),
              "nan": np.full((h, w, 2), np.nan, np.float32),
              "int32": np.ones((h, w, 2), np.int32), "two_d": np.ones((h, w), np.float32),
              "fortran": np.asfortranarray(np.full((h, w, 2), 0.5, np.float32)),
              "many_labels": np.full((h, w, 40), 0.025, np.float32)}
    specs = []
    for name, array in arrays.items():
        def build(d, array=array):
            path = os.path.join(d, "probs.npy")
            np.save(path, array)
            return ["crf", image, path, "--out", os.path.join(d, "o.png")], [file_named(path)]
        specs.append(Spec("crf", f"npy_{name}", build))
    good = os.path.join(inputs["base"], "probs.npy")
    np.save(good, np.full((h, w, 2), 0.5, np.float32))
    for name, data in byte_mutations(rng, read_bytes(good)):
        def build(d, data=data):
            path = os.path.join(d, "probs.npy")
            replace_file(path, data)
            return ["crf", image, path, "--out", os.path.join(d, "o.png")], [file_named(path)]
        specs.append(Spec("crf", f"bytes_{name}", build))
    return specs


def map_specs(rng, inputs):
    """Map files of `moslam run --load-map` (docs/MAP_FORMAT.md): damaged bytes, cuts in the
    header and the body, a directory, an absent file; and the map made with another vocabulary."""
    tum, original = inputs["tum"], inputs["map"]
    settings = os.path.join(tum, "settings.yaml")

    def load(d, path, vocabulary=inputs["vocab_binary"], extra=()):
        return run_args("tum", tum, settings, d,
                        ["--vocabulary", vocabulary, "--load-map", path] + list(extra))

    data = read_bytes(original)
    mutations = byte_mutations(rng, data)
    mutations += [(f"cut_{n}", data[:n]) for n in (8, 12, 23, 24, 40, len(data) - 1)]
    specs = []
    for name, mutated in mutations:
        def build(d, mutated=mutated, name=name):
            path = os.path.join(d, "w_xyz.map")
            replace_file(path, mutated)
            return load(d, path, extra=["--localization"] if "flip" in name else []), \
                [file_named(path)]
        specs.append(Spec("map", f"load_{name}", build, cost=3))

    def other_vocabulary(d):
        # The shipped vocabulary is another tree than the one the map was made with.
        path = clone(original, os.path.join(d, "w_xyz.map"))
        shipped = os.path.join(inputs["repo"], "data", "vocab", "moslam_orb.mvoc")
        return load(d, path, vocabulary=shipped), [file_named(path)]

    def directory(d):
        return load(d, d), [file_named(d)]

    def absent(d):
        path = os.path.join(d, "none.map")
        return load(d, path), [[path]]

    def valid(d):
        return load(d, clone(original, os.path.join(d, "w_xyz.map")), extra=["--localization"]), []
    specs += [Spec("map", "other_vocabulary", other_vocabulary, cost=3),
              Spec("map", "directory", directory, cost=3), Spec("map", "absent", absent, cost=3),
              Spec("map", "valid", valid, cost=3, valid=True)]
    return specs


def specs(inputs, seed):
    rng = random.Random(seed + 3)
    return (mask_specs(rng, inputs) + card_specs(rng, inputs) + model_specs(rng, inputs) +
            vocab_specs(rng, inputs) + crf_specs(rng, inputs) + map_specs(rng, inputs))
