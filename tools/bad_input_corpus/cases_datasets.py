"""Data sets: TUM RGB-D, KITTI, EuRoC and image folders with malformed lists (bad fields, NaN and
out-of-order stamps, truncation, garbage), damaged images (truncated, empty, wrong format, wrong
size, wrong depth) and broken layouts; read by `moslam dataset info --check-images`, a part also by
`moslam run`."""

import os
import random

import cv2
import numpy as np

from helpers import Spec, clone, damaged_line_names, file_named, read_lines, write_lines
from mutate import byte_mutations, line_mutations, read_bytes, replace_file, substitute_path

def info_args(fmt, root, settings=None, extra=()):
    args = ["dataset", "info", root, "--format", fmt, "--check-images"] + list(extra)
    return args + (["--settings", settings] if settings else [])


def run_args(fmt, root, settings, d, extra=()):
    return (["run", "--dataset", fmt, root, "--settings", settings, "--out", os.path.join(d, "out"),
             "--quiet", "--no-loop-closing"] + list(extra))


def list_specs(rng, reader, fmt, base, rel_list, sep=" ", extra=None, max_fields=4):
    """Every line mutation of base/rel_list; extra(root) gives more arguments."""
    lines = read_lines(os.path.join(base, rel_list))
    specs = []
    for name, mutated, pick in line_mutations(rng, lines, sep, max_fields):
        def build(d, mutated=mutated, pick=pick):
            root = clone(base, os.path.join(d, "seq"))
            path = os.path.join(root, rel_list)
            write_lines(path, mutated)
            args = info_args(fmt, root, extra=extra(root) if extra else ())
            return args, damaged_line_names(path, lines, pick)
        specs.append(Spec(reader, f"{rel_list.replace('/', '_')}_{name}", build))
    return specs


def image_variants(rng, path, depth=False):
    """(name, bytes) of damaged images for the image at `path`."""
    image = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    h, w = image.shape[:2]
    out = list(byte_mutations(rng, read_bytes(path)))

    def png(img):
        return cv2.imencode(".png", img)[1].tobytes()
    out.append(("smaller", png(cv2.resize(image, (w // 2, h // 2)))))
    out.append(("larger", png(cv2.resize(image, (w * 2, h)))))
    out.append(("one_pixel", png(image[:1, :1])))
    out.append(("jpeg_named_png", cv2.imencode(".jpg", image if not depth else
                                               (image // 256).astype(np.uint8))[1].tobytes()))
    if depth:
        out.append(("depth_8bit", png((image // 256).astype(np.uint8))))
        out.append(("depth_3channel", png(np.dstack([image] * 3))))
        out.append(("depth_all_zero", png(np.zeros_like(image))))
    else:
        grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        out.append(("grey", png(grey)))
        out.append(("16bit", png(image.astype(np.uint16) * 257)))
        out.append(("four_channel", png(cv2.cvtColor(grey, cv2.COLOR_GRAY2BGRA))))
    return out


def image_specs(rng, reader, fmt, base, rel_image, depth=False, settings=None, runs=0):
    """Damaged versions of one image of the data set: all through `dataset info --check-images`,
    the first `runs` of them also through `moslam run`."""
    specs = []
    variants = image_variants(rng, os.path.join(base, rel_image), depth)
    variants += [("missing", None), ("directory", "dir")]
    for k, (name, data) in enumerate(variants):
        def build(d, data=data, use_run=False):
            root = clone(base, os.path.join(d, "seq"))
            path = os.path.join(root, rel_image)
            substitute_path(path, data)
            s = os.path.join(root, "settings.yaml") if settings else None
            args = run_args(fmt, root, s, d) if use_run else info_args(fmt, root)
            return args, [file_named(path)]
        tag = f"{rel_image.replace('/', '_')}_{name}"
        specs.append(Spec(reader, tag, build))
        if k < runs and settings:
            specs.append(Spec(reader, f"run_{tag}", lambda d, b=build: b(d, use_run=True), cost=3))
    return specs


def layout_specs(reader, fmt, base, removals, settings=False):
    """The data set with one file or folder removed (or emptied)."""
    specs = []
    for rel in removals:
        def build(d, rel=rel):
            root = clone(base, os.path.join(d, "seq"))
            path = os.path.join(root, rel)
            if os.path.isdir(path):
                import shutil
                shutil.rmtree(path)
                os.makedirs(path)
            else:
                os.unlink(path)
            return info_args(fmt, root), [file_named(path) + [root]]
        specs.append(Spec(reader, f"layout_no_{rel.replace('/', '_')}", build))

    def absent(d):
        return info_args(fmt, os.path.join(d, "none")), [[os.path.join(d, "none")]]

    def valid(d):
        root = clone(base, os.path.join(d, "seq"))
        s = os.path.join(root, "settings.yaml") if settings else None
        return info_args(fmt, root, s), []
    specs += [Spec(reader, "layout_absent", absent), Spec(reader, "valid", valid, valid=True)]
    return specs


def tum_specs(rng, tum):
    specs = []
    for rel in ("rgb.txt", "depth.txt", "groundtruth.txt"):
        specs += list_specs(rng, "tum", "tum", tum, rel)
    specs += list_specs(rng, "tum", "tum", tum, "associations.txt",
                        extra=lambda root: ("--associations",
                                            os.path.join(root, "associations.txt")))
    first = sorted(os.listdir(os.path.join(tum, "rgb")))
    specs += image_specs(rng, "tum", "tum", tum, "rgb/" + first[3], settings=True, runs=8)
    specs += image_specs(rng, "tum", "tum", tum, "depth/" + first[5], depth=True, settings=True,
                         runs=5)
    specs += layout_specs("tum", "tum", tum, ["rgb.txt", "depth.txt", "rgb", "depth"],
                          settings=True)
    return specs


def kitti_specs(rng, kitti):
    specs = list_specs(rng, "kitti", "kitti", kitti, "times.txt")
    specs += list_specs(rng, "kitti", "kitti", kitti, "calib.txt", max_fields=5)
    specs += image_specs(rng, "kitti", "kitti", kitti, "image_0/000002.png", settings=True, runs=4)
    specs += image_specs(rng, "kitti", "kitti", kitti, "image_1/000004.png", settings=True, runs=2)
    specs += layout_specs("kitti", "kitti", kitti,
                          ["times.txt", "calib.txt", "image_0", "image_1/000003.png"],
                          settings=True)
    return specs


def euroc_specs(rng, euroc):
    specs = list_specs(rng, "euroc", "euroc", euroc, "mav0/cam0/data.csv", sep=",")
    specs += list_specs(rng, "euroc", "euroc", euroc, "mav0/cam1/data.csv", sep=",")
    name = sorted(os.listdir(os.path.join(euroc, "mav0/cam0/data")))[2]
    specs += image_specs(rng, "euroc", "euroc", euroc, "mav0/cam0/data/" + name)
    specs += layout_specs("euroc", "euroc", euroc, ["mav0/cam0/data.csv", "mav0/cam1/data"])
    return specs


def folder_specs(rng, folder, kitti):
    specs = []
    name = sorted(os.listdir(folder))[1]
    for variant, data in image_variants(rng, os.path.join(folder, name)):
        def build(d, data=data, use_run=False):
            root = clone(folder, os.path.join(d, "images"))
            path = os.path.join(root, name)
            replace_file(path, data)
            if use_run:
                s = os.path.join(kitti, "settings.yaml")
                return run_args("folder", root, s, d, ["--monocular"]), [file_named(path)]
            return info_args("folder", root, extra=("--rate", "10")), [file_named(path)]
        specs.append(Spec("folder", f"{variant}", build))
        if variant in ("truncated_50pct", "smaller", "text", "16bit"):
            specs.append(Spec("folder", f"run_{variant}", lambda d, b=build: b(d, use_run=True), cost=3))

    def empty(d):
        root = os.path.join(d, "images")
        os.makedirs(root)
        return info_args("folder", root, extra=("--rate", "10")), [[root]]

    def no_rate(d):
        root = clone(folder, os.path.join(d, "images"))
        return info_args("folder", root), [["--rate", "rate"]]
    specs += [Spec("folder", "empty_folder", empty), Spec("folder", "no_rate", no_rate)]
    return specs


def specs(inputs, seed):
    rng = random.Random(seed + 1)
    return (tum_specs(rng, inputs["tum"]) + kitti_specs(rng, inputs["kitti"]) +
            euroc_specs(rng, inputs["euroc"]) + folder_specs(rng, inputs["folder"], inputs["kitti"]))
