# SPDX-License-Identifier: AGPL-3.0-or-later
"""The metadata of every submodel against docs/metadata.schema.json (docs/metadata.md).

Renders one tiny scene per submodel (pinhole / none, thin / none, camera array, thin main lens
with pinhole, thin hexagonal and thin rectangular microlenses, pinhole main lens with thin
microlenses, multi-focus, posed array, depth map on, adaptive samples) and checks each
<image>.plenoptic.json:
  - it is strict JSON in UTF-8 (no duplicate key, no lone surrogate, no NaN) and matches the schema;
  - its members come in the documented order;
  - every number is in its shortest round-trip form (0.15, never 0.14999999999999999);
  - the fields that tell the submodels apart say what the scene asked for.
Then shows the schema can fail: mutated copies of a real document (a wrong enum, a missing or an
extra field, a wrong array length, null where a number is required, a number as a string, a
lattice without an array, ...) must each be refused. The golden references
(tests/golden/references) must match the schema too.
"""

import argparse
import copy
import glob
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import metadata_schema  # noqa: E402

REFERENCES = os.path.join(HERE, "..", "golden", "references")

HEADER = """#version 3.7;
global_settings { assumed_gamma 1.0 }
sky_sphere { pigment { rgb <0.6, 0.7, 0.9> } }
sphere { <0, 0, 0>, 0.3 pigment { checker rgb 1 rgb <1, 0.2, 0.1> scale 0.1 } finish { emission 1 diffuse 0 } }
"""

THIN = "main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }"

# name: (camera body, what the metadata must say: dotted path -> value)
SCENES = {
    "pinhole_none": ("main_lens { pinhole distance 16 }",
                     {"main_lens.type": "pinhole", "microlens_array": None, "microimage_lattice": None,
                      "main_lens.focal_length_mm": None, "main_lens.distance_mm": 16}),
    "thin_none": (THIN + " samples 4",
                  {"main_lens.type": "thin_lens", "main_lens.focal_length_mm": 16, "main_lens.f_number": 4,
                   "main_lens.focus_distance": 2, "microlens_array": None, "lftoolbox_lenslet_grid_model": None}),
    "none_pinhole_array": ("microlens_array { rectangular pitch 0.3 pinhole distance 1.5 }",
                           {"main_lens.type": "none", "main_lens.distance_mm": None,
                            "microlens_array.lens": "pinhole", "microlens_array.focal_lengths_mm": [],
                            "microimage_lattice.microimage_diameter_px": None}),
    "thin_pinhole": (THIN + " microlens_array { hexagonal pitch 0.15 pinhole distance 0.6 }",
                     {"microlens_array.grid": "hexagonal", "microlens_array.lens": "pinhole",
                      "microlens_array.pitch_mm": 0.15}),
    "thin_thin_hexagonal": (THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }"
                            " samples 4",
                            {"microlens_array.focal_lengths_mm": [0.6], "microimage_lattice.lens_types": 1,
                             "lftoolbox_lenslet_grid_model.Orientation": "horz"}),
    "thin_thin_rectangular": (THIN + " microlens_array { rectangular pitch 0.15 focal_length 0.5 distance 0.575 }"
                              " samples 4",
                              {"microlens_array.grid": "rectangular", "microlens_array.distance_mm": 0.575,
                               "lftoolbox_lenslet_grid_model.FirstPosShiftRow": None}),
    "pinhole_thin": ("main_lens { pinhole distance 16 } microlens_array { hexagonal pitch 0.15 focal_length 0.6"
                     " distance 0.6 } samples 4",
                     {"main_lens.type": "pinhole", "microlens_array.lens": "thin_lens",
                      "microimage_lattice.microimage_diameter_px": None}),
    "multifocus": (THIN + " microlens_array { hexagonal pitch 0.15 focal_lengths <0.6, 0.7, 0.8> distance 0.6 }"
                   " samples 4",
                   {"microlens_array.focal_lengths_mm": [0.6, 0.7, 0.8], "microimage_lattice.lens_types": 3}),
    "posed_array": (THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6"
                    " rotate <0, 0, 7> translate <0.25, -0.1, 0> } samples 4",
                    {"microlens_array.rotate_deg": [0, 0, 7], "microlens_array.translate_mm": [0.25, -0.1, 0],
                     "microimage_lattice.exact": True}),
    "depth_map_on": (THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }"
                     " samples 4 depth_map",
                     {"depth_map": "depth_map_on.depth.exr"}),
    "adaptive": (THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }"
                 " samples 2, 8 confidence 0.95 variance 0.01",
                 {"samples.adaptive": True, "samples.min": 2, "samples.max": 8, "samples.confidence": 0.95,
                  "samples.variance": 0.01}),
}

ORDER = {
    "": ["format", "version", "image", "mm_per_unit", "camera_frame", "main_lens", "microlens_array", "sensor",
         "samples", "principal_point_px", "microimage_lattice", "lftoolbox_lenslet_grid_model", "depth_map"],
    "image": ["width", "height"],
    "camera_frame": ["location", "right", "up", "direction"],
    "main_lens": ["type", "focal_length_mm", "aperture_mm", "f_number", "distance_mm", "focus_distance"],
    "microlens_array": ["grid", "lens", "pitch_mm", "focal_lengths_mm", "distance_mm", "rotate_deg", "translate_mm"],
    "sensor": ["pixel_size_mm", "offset_mm", "plane_z_mm"],
    "samples": ["adaptive", "min", "max", "confidence", "variance"],
    "microimage_lattice": ["origin_px", "basis_px", "index_rule", "exact", "lens_types", "lens_type_rule",
                           "microimage_diameter_px"],
    "lftoolbox_lenslet_grid_model": ["HSpacing", "VSpacing", "HOffset", "VOffset", "Rot", "Orientation",
                                     "FirstPosShiftRow", "UMax", "VMax"],
}

NUMBER = re.compile(r'"(?:[^"\\]|\\.)*"|(-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?)')


def significant(token):
    """Significant digits of a decimal: '0.0078125' -> '78125', '1e+300' -> '1', '1000' -> '1'."""
    digits = re.sub(r"[^0-9]", "", re.split(r"[eE]", token)[0]).strip("0")
    return digits or "0"


def not_shortest(text):
    """Number tokens of a JSON text with more significant digits than the shortest round trip."""
    bad = []
    for m in NUMBER.finditer(text):
        token = m.group(1)
        if token is not None and significant(token) != significant(repr(float(token))):
            bad.append("%s (shortest: %r)" % (token, float(token)))
    return bad


def get(doc, path):
    node = doc
    for part in path.split("."):
        node = node[part]
    return node


def render(args, name, body):
    work = args.work
    pov = os.path.join(work, name + ".pov")
    out = os.path.join(work, name + ".png")
    for stale in (out, os.path.join(work, name + ".plenoptic.json"), os.path.join(work, name + ".depth.exr")):
        if os.path.exists(stale):
            os.remove(stale)
    with open(pov, "w") as f:
        f.write(HEADER + "camera {\n  plenoptic\n  location <0, 0, -2>\n  look_at <0, 0, 0>\n  sensor { "
                "pixel_size 0.02 }\n  %s\n}\n" % body)
    cmd = [args.povray, "+I" + name + ".pov", "+O" + name + ".png", "+W48", "+H36", "-D", "-P", "-V", "+WT1"]
    run = subprocess.run(cmd, cwd=work, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    if run.returncode != 0:
        raise RuntimeError("render of %s failed (exit %d):\n%s" % (name, run.returncode,
                                                                   run.stdout.decode(errors="replace")[-2000:]))
    return os.path.join(work, name + ".plenoptic.json")


def mutations(doc):
    """(label, broken copy) pairs that the schema must refuse; built from a plenoptic document."""
    def with_(edit):
        d = copy.deepcopy(doc)
        edit(d)
        return d

    def setter(path, value):
        def edit(d):
            parts = path.split(".")
            node = d
            for p in parts[:-1]:
                node = node[p]
            node[parts[-1]] = value
        return edit

    def dropper(path):
        def edit(d):
            parts = path.split(".")
            node = d
            for p in parts[:-1]:
                node = node[p]
            del node[parts[-1]]
        return edit

    hexagonal = doc["microlens_array"]["grid"] == "hexagonal"
    other_rule = ("skew indices (k, l): %s centres in the array are k*(p,0) + %s"
                  % (("rectangular", "l*(0,p)") if hexagonal else ("hexagonal", "l*(p/2, p*sqrt(3)/2)")))
    other_shift = None if hexagonal else 1
    return [
        ("unknown main-lens type", with_(setter("main_lens.type", "fisheye"))),
        ("unknown grid", with_(setter("microlens_array.grid", "triangular"))),
        ("wrong format", with_(setter("format", "something-else"))),
        ("version 2", with_(setter("version", 2))),
        ("missing field", with_(dropper("sensor.plane_z_mm"))),
        ("missing top-level field", with_(dropper("depth_map"))),
        ("extra field", with_(setter("sensor.temperature", 20))),
        ("extra top-level field", with_(setter("comment", "hello"))),
        ("two-element location", with_(setter("camera_frame.location", [0, 0]))),
        ("three-element pixel size", with_(setter("sensor.pixel_size_mm", [0.01, 0.01, 0.01]))),
        ("two focal lengths", with_(setter("microlens_array.focal_lengths_mm", [0.6, 0.7]))),
        ("null pitch", with_(setter("microlens_array.pitch_mm", None))),
        ("negative pitch", with_(setter("microlens_array.pitch_mm", -0.15))),
        ("number as a string", with_(setter("mm_per_unit", "1000"))),
        ("fractional width", with_(setter("image.width", 48.5))),
        ("boolean as a number", with_(setter("microimage_lattice.exact", 1))),
        ("thin lens without focal length", with_(setter("main_lens.focal_length_mm", None))),
        ("pinhole with a focal length", with_(setter("main_lens.type", "pinhole"))),
        ("lattice without an array", with_(setter("microlens_array", None))),
        ("three lens types with one focal length", with_(setter("microimage_lattice.lens_types", 3))),
        ("the other grid's index rule", with_(setter("microimage_lattice.index_rule", other_rule))),
        ("row shift 3", with_(setter("lftoolbox_lenslet_grid_model.FirstPosShiftRow", 3))),
        ("the other grid's row shift", with_(setter("lftoolbox_lenslet_grid_model.FirstPosShiftRow", other_shift))),
        ("confidence 1", with_(setter("samples.confidence", 1))),
        ("empty depth map name", with_(setter("depth_map", ""))),
        ("sensor in front of the lens", with_(setter("sensor.plane_z_mm", 1.0))),
        ("an array at the top", [doc]),
    ]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--povray", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    failures = []

    def check(ok, message):
        print(("ok    " if ok else "FAIL  ") + message)
        if not ok:
            failures.append(message)

    docs = {}
    for name, (body, expect) in SCENES.items():
        path = render(args, name, body)
        try:
            doc = metadata_schema.load(path)
        except metadata_schema.MetadataError as e:
            check(False, "%s: %s" % (name, e))
            continue
        docs[name] = doc
        check(True, "%s: strict JSON, matches the schema" % name)
        with open(path, encoding="utf-8") as f:
            text = f.read()
        wrong_order = [p or "(top level)" for p, keys in ORDER.items()
                       if isinstance(get(doc, p) if p else doc, dict) and list((get(doc, p) if p else doc)) != keys]
        check(not wrong_order, "%s: members in the documented order (wrong in %s)" % (name, wrong_order))
        bad = not_shortest(text)
        check(not bad, "%s: every number in its shortest round-trip form (not: %s)" % (name, bad[:5]))
        wrong = {p: get(doc, p) for p, v in expect.items() if get(doc, p) != v}
        check(not wrong, "%s: says what the scene asked for (wrong: %r)" % (name, wrong))

    # The schema can fail: mutated copies of real documents.
    for source in ("thin_thin_hexagonal", "multifocus", "none_pinhole_array"):
        if source not in docs:
            continue
        for label, broken in mutations(docs[source]):
            if source == "multifocus" and label in ("two focal lengths", "three lens types with one focal length"):
                continue
            if source == "none_pinhole_array" and label in ("thin lens without focal length",):
                continue
            problems = metadata_schema.schema_errors(broken)
            check(bool(problems), "%s, %s: refused by the schema (%s)" % (source, label, "; ".join(problems[:2])))
    if "multifocus" in docs:
        broken = copy.deepcopy(docs["multifocus"])
        broken["microimage_lattice"]["lens_types"] = 1
        broken["microimage_lattice"]["lens_type_rule"] = "type(k, l) = 0"
        problems = metadata_schema.schema_errors(broken)
        check(bool(problems), "multifocus, one lens type with three focal lengths: refused (%s)" % problems[:1])

    # The strict reading refuses what Python's json would let through.
    good = json.dumps(docs.get("thin_thin_hexagonal", {}))
    for label, data in (("duplicate key", good.replace('"version": 1,', '"version": 1, "version": 1,', 1)),
                        ("lone surrogate", good.replace('"depth_map": null', '"depth_map": "\\ud800.exr"')),
                        ("invalid UTF-8", good.replace('"depth_map": null', '"depth_map": "caf\xe9.exr"')
                         .encode("latin-1")),
                        ("NaN", good.replace('"mm_per_unit": 1000', '"mm_per_unit": NaN'))):
        try:
            metadata_schema.parse(data, "mutated")
            check(False, "strict reading, %s: accepted" % label)
        except metadata_schema.MetadataError as e:
            check(True, "strict reading, %s: refused (%s)" % (label, e))

    # The golden references (written by earlier builds) match the schema too.
    references = sorted(glob.glob(os.path.join(REFERENCES, "*.plenoptic.json")))
    for ref in references:
        try:
            metadata_schema.load(ref)
        except metadata_schema.MetadataError as e:
            check(False, "golden reference %s: %s" % (os.path.basename(ref), e))
    check(len(references) > 0, "%d golden references match the schema" % len(references))

    if failures:
        print("metadata_schema: %d check(s) failed" % len(failures))
        return 1
    print("metadata_schema: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
