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

import copy
import glob
import json
import os
import re

import pytest

import plenoptic_testing as pt

REFERENCES = os.path.join(pt.GOLDEN_DIR, "references")

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
                     {"depth_map": "depth_map_on.depth.exr", "virtual_depth_map": None}),
    "virtual_depth_on": (THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.75 }"
                         " samples 4 depth_map",
                         {"depth_map": "virtual_depth_on.depth.exr",
                          "virtual_depth_map": "virtual_depth_on.virtual_depth.exr"}),
    "adaptive": (THIN + " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }"
                 " samples 2, 8 confidence 0.95 variance 0.01",
                 {"samples.adaptive": True, "samples.min": 2, "samples.max": 8, "samples.confidence": 0.95,
                  "samples.variance": 0.01}),
}

ORDER = {
    "": ["format", "version", "image", "mm_per_unit", "camera_frame", "main_lens", "microlens_array", "sensor",
         "samples", "diffraction", "principal_point_px", "microimage_lattice", "lftoolbox_lenslet_grid_model", "depth_map",
         "virtual_depth_map", "microimages", "white_images"],
    "image": ["width", "height"],
    "camera_frame": ["location", "right", "up", "direction"],
    "main_lens": ["type", "focal_length_mm", "aperture_mm", "f_number", "distance_mm", "focus_distance",
                  "distortion_profile"],
    "main_lens.distortion_profile": ["object_plane_z_mm", "image_plane_z_mm", "chief_ray", "columns", "samples"],
    "microlens_array": ["grid", "lens", "pitch_mm", "focal_lengths_mm", "distance_mm", "rotate_deg", "translate_mm"],
    "sensor": ["pixel_size_mm", "offset_mm", "plane_z_mm", "radiometry", "read_out"],
    "sensor.radiometry": ["model", "projected_solid_angle_sr", "angular_response"],
    "samples": ["adaptive", "min", "max", "confidence", "variance"],
    "diffraction": ["model", "aperture", "aperture_diameter_mm", "distance_mm", "wavelengths_nm", "airy_radius_um",
                    "airy_radius_px", "kernel_radius_airy_radii", "main_lens_airy_radius_at_array_um"],
    "microimage_lattice": ["origin_px", "basis_px", "index_rule", "exact", "lens_types", "lens_type_rule",
                           "microimage_diameter_px"],
    "lftoolbox_lenslet_grid_model": ["HSpacing", "VSpacing", "HOffset", "VOffset", "Rot", "Orientation",
                                     "FirstPosShiftRow", "UMax", "VMax"],
    "microimages": ["file", "columns", "lenses", "lit_lenses", "integration", "lattice_fit", "from_microimage_lattice"],
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
    text = (HEADER + "camera {\n  plenoptic\n  location <0, 0, -2>\n  look_at <0, 0, 0>\n  sensor { "
            "pixel_size 0.02 }\n  %s\n}\n" % body)
    pt.render(args.povray, args.work, name, text, 48, 36, options=("-D", "-P", "-V", "+WT1"), relative=True)
    return os.path.join(args.work, name + ".plenoptic.json")


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


@pytest.fixture(scope="module")
def docs(args):
    """name -> the metadata of its render, or the MetadataError reading it raised."""
    out = {}
    for name, (body, _) in SCENES.items():
        path = render(args, name, body)
        try:
            out[name] = pt.load_metadata(path)
        except pt.MetadataError as e:
            out[name] = e
    return out


def rendered(docs, name):
    doc = docs[name]
    assert not isinstance(doc, Exception), "%s: %s" % (name, doc)
    return doc


@pytest.mark.parametrize("name", list(SCENES))
def test_submodel_metadata(args, docs, name):
    doc = rendered(docs, name)  # strict JSON, matches the schema
    expect = SCENES[name][1]
    with open(os.path.join(args.work, name + ".plenoptic.json"), encoding="utf-8") as f:
        text = f.read()
    wrong_order = [p or "(top level)" for p, keys in ORDER.items()
                   if isinstance(get(doc, p) if p else doc, dict) and list((get(doc, p) if p else doc)) != keys]
    assert not wrong_order, "%s: members in the documented order (wrong in %s)" % (name, wrong_order)
    bad = not_shortest(text)
    assert not bad, "%s: every number in its shortest round-trip form (not: %s)" % (name, bad[:5])
    wrong = {p: get(doc, p) for p, v in expect.items() if get(doc, p) != v}
    assert not wrong, "%s: says what the scene asked for (wrong: %r)" % (name, wrong)


@pytest.mark.parametrize("source", ["thin_thin_hexagonal", "multifocus", "none_pinhole_array"])
def test_schema_refuses_mutations(docs, source):
    """The schema can fail: mutated copies of real documents."""
    accepted = []
    for label, broken in mutations(rendered(docs, source)):
        if source == "multifocus" and label in ("two focal lengths", "three lens types with one focal length"):
            continue
        if source == "none_pinhole_array" and label in ("thin lens without focal length",):
            continue
        if not pt.schema_errors(broken):
            accepted.append(label)
    assert not accepted, "%s: mutated copies the schema does not refuse: %s" % (source, accepted)


def test_one_lens_type_with_three_focal_lengths_refused(docs):
    broken = copy.deepcopy(rendered(docs, "multifocus"))
    broken["microimage_lattice"]["lens_types"] = 1
    broken["microimage_lattice"]["lens_type_rule"] = "type(k, l) = 0"
    problems = pt.schema_errors(broken)
    assert problems, "multifocus, one lens type with three focal lengths: accepted by the schema"


STRICT_CASES = ["duplicate key", "lone surrogate", "invalid UTF-8", "NaN"]


@pytest.mark.parametrize("label", STRICT_CASES)
def test_strict_reading_refuses(docs, label):
    """The strict reading refuses what Python's json would let through."""
    good = json.dumps(rendered(docs, "thin_thin_hexagonal"))
    data = {"duplicate key": good.replace('"version": 1,', '"version": 1, "version": 1,', 1),
            "lone surrogate": good.replace('"depth_map": null', '"depth_map": "\\ud800.exr"'),
            "invalid UTF-8": good.replace('"depth_map": null', '"depth_map": "caf\xe9.exr"').encode("latin-1"),
            "NaN": good.replace('"mm_per_unit": 1000', '"mm_per_unit": NaN')}[label]
    assert data != good, "strict reading, %s: the mutation did not apply" % label
    with pytest.raises(pt.MetadataError):
        pt.parse_json_strict(data, "mutated")


def test_golden_references_match_schema():
    """The golden references (written by earlier builds) match the schema too."""
    references = sorted(glob.glob(os.path.join(REFERENCES, "*.plenoptic.json")))
    problems = []
    for ref in references:
        try:
            pt.load_metadata(ref)
        except pt.MetadataError as e:
            problems.append("golden reference %s: %s" % (os.path.basename(ref), e))
    assert not problems, "\n".join(problems)
    assert len(references) > 0, "%d golden references match the schema" % len(references)


# A dispersing real lens and dispersing microlenses (docs/real-lenses.md, "Dispersion"): an N-BK7
# singlet (SCHOTT: n_d 1.51680, V_d 64.17) behind a stop, its Abbe number inline.
DISPERSIVE = ("main_lens { prescription { stop { thickness 2 aperture 8 }"
              " surface { radius 30 thickness 5 ior 1.5168 aperture 20 abbe 64.17 }"
              " surface { radius -30 thickness 0 ior 1 aperture 20 } } focus_distance 2 }"
              " microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 abbe 58 } samples 2")


def test_dispersive_lens_metadata(args):
    """The glass and the focus at the F, d and C lines are written, match the schema, and the
    schema refuses them broken."""
    doc = pt.load_metadata(render(args, "dispersive", DISPERSIVE))
    surfaces = doc["main_lens"]["prescription"]["surfaces"]
    assert [s.get("abbe_number") for s in surfaces] == [None, 64.17, None]
    assert doc["microlens_array"]["abbe_number"] == 58
    lines = doc["main_lens"]["paraxial"]["lines"]
    assert list(lines) == ["F", "d", "C"]
    assert [lines[k]["wavelength_nm"] for k in "FdC"] == [486.1327, 587.5618, 656.2725]
    # An undercorrected singlet: blue focuses nearer, by about f / V_d.
    f = doc["main_lens"]["paraxial"]["effective_focal_length_mm"]
    colour = doc["main_lens"]["paraxial"]["longitudinal_colour_mm"]
    assert colour == lines["F"]["back_focal_distance_mm"] - lines["C"]["back_focal_distance_mm"]
    assert -1.2 * f / 64.17 < colour < -0.8 * f / 64.17, (colour, f)
    assert lines["F"]["effective_focal_length_mm"] < lines["d"]["effective_focal_length_mm"] < lines["C"]["effective_focal_length_mm"]

    def broken(edit):
        d = copy.deepcopy(doc)
        edit(d)
        return d
    for label, bad in [
        ("Abbe number 2", broken(lambda d: d["main_lens"]["prescription"]["surfaces"][1].update(abbe_number=2))),
        ("a line missing", broken(lambda d: d["main_lens"]["paraxial"]["lines"].pop("C"))),
        ("a line without its wavelength", broken(lambda d: d["main_lens"]["paraxial"]["lines"]["F"].pop("wavelength_nm"))),
        ("sellmeier with two terms", broken(lambda d: d["main_lens"]["prescription"]["surfaces"][1].update(
            sellmeier={"b": [1, 0.2], "c_um2": [0.006, 0.02, 103]}))),
        ("microlens Abbe number 500", broken(lambda d: d["microlens_array"].update(abbe_number=500))),
    ]:
        with pytest.raises(pt.MetadataError):
            pt.validate(bad, label)
