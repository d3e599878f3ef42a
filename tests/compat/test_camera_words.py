# SPDX-License-Identifier: AGPL-3.0-or-later
"""The plenoptic camera's words are not reserved words (docs/specification.md, section 6).

Only `plenoptic` is new at the top level of the scene language; every other keyword of the
camera is recognised only inside `camera { plenoptic ... }`. Three checks:

1. A scene with a stock camera that declares every camera word as an identifier (floats,
   vectors, an object, a texture, a string, an array, a macro, a macro parameter, #local)
   and uses each one renders with our build exactly as with Debian's povray.
2. A plenoptic camera written with identifiers named like its own keywords as values
   (`pitch pitch / 100`) gives the same image and the same metadata as the same camera
   written with literal numbers.
3. Declared identifiers of every other kind, named like the block words (`sensor` an object,
   `main_lens` a vector...), do not stop those words from working as keywords.

The words come from the parser's own keyword table (source/povray_glue/plenoptic_keywords.cpp,
listed by plenoptic-keyword-table from --build-dir): its words that are not POV-Ray reserved
words, so a keyword added later is covered without editing this test; the words known when the
test was written must all be in that table.
"""
import os

import numpy as np
import pytest

import plenoptic_testing as pt
from plenoptic_testing.keywords import keyword_table

KNOWN_WORDS = {"main_lens", "microlens_array", "sensor", "thin_lens", "pinhole", "focal_length",
               "focal_lengths", "f_number", "focus_distance", "hexagonal", "rectangular", "pitch",
               "pixel_size", "depth_map", "microimage_centres"}


def camera_words(build_dir):
    """The table's words that are the camera's own (not POV-Ray reserved words), each once."""
    return sorted({k.word for k in keyword_table(build_dir) if not k.reserved})


def render(povray, scene_text, name, work, width=96, height=72, extra=()):
    """(8-bit pixels as int16, or None when the render fails; the console text)."""
    scene = pt.write_text(os.path.join(work, name + ".pov"), scene_text)
    image = os.path.join(work, name + ".png")
    pt.remove_outputs(work, name)
    res = pt.run_povray(povray, scene, image, width, height, extra, timeout=300, cwd=work,
                        options=("-D", "-P", "+FN8", "-GS", "-GR", "+WT1"))
    out = res.output
    if res.returncode != 0 or res.timed_out or not os.path.exists(image):
        return None, out
    return pt.read_pixels(image, native=True).astype(np.int16), out  # an 8-bit PNG (+FN8): its values


def identifiers_scene(words):
    """A stock-camera scene: every word a declared float used in the picture, and the first
    few words re-declared as identifiers of other kinds."""
    lines = ['#version 3.7;', 'global_settings { assumed_gamma 1.0 }',
             'camera { perspective location <0, 1.2, -6> look_at <0, 0.6, 0> angle 50 }',
             'light_source { <-4, 8, -6> rgb 1 }', 'plane { y, 0 pigment { checker rgb 0.2 rgb 0.8 } }',
             # A macro parameter named like a camera word (parameters must be undeclared names).
             '#macro post(hexagonal, height) cylinder { <hexagonal, 0, 1>, <hexagonal, height, 1>, 0.1 '
             'pigment { rgb <0.2, 0.4, 1> } } #end',
             # A macro named like a camera word (a name declared as a float cannot become a macro).
             '#macro pinhole(xpos) post(xpos, f_number[2] * 4 + strlen(focal_length) / 10) #end']
    floats = [w for w in words if w != "pinhole"]
    n = len(floats)
    for i, w in enumerate(floats):
        lines.append("#declare %s = %.3f;" % (w, (i + 0.5) / n))
        lines.append("sphere { <%s * 6 - 3, %s * 0.5 + 0.2, 0>, 0.15 pigment { rgb <%s, 1 - %s, 0.5> } }"
                     % (w, w, w, w))
    # Other kinds of identifier under the same names (redeclaring changes their type).
    lines += [
        '#declare pitch = <0.2, 1.6, 1>;',
        '#declare sensor = box { -0.3, 0.3 rotate 30 * y }',
        '#declare main_lens = texture { pigment { rgb pitch } }',
        'object { sensor texture { main_lens } translate pitch }',
        '#declare focal_length = "label";',
        '#declare f_number = array[3] { 0.1, 0.2, 0.3 }',
        'pinhole(-1.5)',
        'pinhole(1.5)',
        '#local depth_map = 2;',
        'torus { 0.4, 0.05 rotate 90 * x translate <0, depth_map * 0.6, 2> pigment { rgb <1, 0.6, 0> } }',
    ]
    return "\n".join(lines) + "\n"


CAMERA_LITERAL = """#version 3.7;
global_settings { assumed_gamma 1.0 }
light_source { <-3, 6, -4> rgb 1 }
plane { y, 0 pigment { checker rgb 0.2 rgb 0.9 scale 0.25 } }
sphere { <0, 0.4, 0>, 0.4 pigment { rgb <0.9, 0.3, 0.2> } }
camera {
  plenoptic
  location <0, 0.5, -2> look_at <0, 0.3, 0>
  main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }
  sensor { pixel_size 0.01 }
  samples 4
  depth_map
}
"""

# The same camera, every value given by an identifier named like a keyword of the camera.
CAMERA_IDENTIFIERS = """#version 3.7;
#declare pitch = 15;               // hundredths of a millimetre
#declare focal_length = 0.6;
#declare main_lens = 16;
#declare f_number = 4;
#declare focus_distance = 2;
#declare sensor = 0.01;
#declare pixel_size = sensor;
#declare microlens_array = 0.6;
#declare hexagonal = 1;
#declare thin_lens = 0;
#declare depth_map = 1;
global_settings { assumed_gamma 1.0 }
light_source { <-3, 6, -4> rgb 1 }
plane { y, 0 pigment { checker rgb 0.2 rgb 0.9 scale 0.25 } }
sphere { <0, 0.4, 0>, 0.4 pigment { rgb <0.9, 0.3, 0.2> } }
camera {
  plenoptic
  location <0, 0.5, -2> look_at <0, 0.3, 0>
  main_lens { thin_lens focal_length main_lens f_number f_number focus_distance focus_distance }
  microlens_array { hexagonal pitch pitch / 100 focal_length focal_length distance microlens_array }
  sensor { pixel_size pixel_size }
  samples 4
  depth_map
}
"""

# Block words declared as identifiers of other kinds; the camera must still read them as keywords.
CAMERA_OTHER_KINDS = """#version 3.7;
#declare sensor = sphere { 0, 1 }
#declare main_lens = <1, 2, 3>;
#declare microlens_array = texture { pigment { rgb 1 } }
#declare pinhole = "a string";
#declare rectangular = array[2] { 1, 2 }
global_settings { assumed_gamma 1.0 }
light_source { <-3, 6, -4> rgb 1 }
plane { y, 0 pigment { checker rgb 0.2 rgb 0.9 scale 0.25 } }
sphere { <0, 0.4, 0>, 0.4 pigment { rgb <0.9, 0.3, 0.2> } }
camera {
  plenoptic
  location <0, 0.5, -2> look_at <0, 0.3, 0>
  depth_map
  main_lens { thin_lens focal_length 16 f_number 4 focus_distance 2 }
  microlens_array { hexagonal pitch 0.15 focal_length 0.6 distance 0.6 }
  sensor { pixel_size 0.01 }
  samples 4
}
"""


def compare(a, b, what, max_diff=0, max_fraction=0.0):
    if a is None or b is None or a.shape != b.shape:
        return ["%s: images missing or of different shapes" % what]
    diff = np.abs(a - b)
    fraction = float(np.mean(diff.max(axis=2) > 0))
    print("%s: largest difference %d/255, %.3f %% of pixels differ" % (what, diff.max(), 100 * fraction))
    if diff.max() > max_diff or fraction > max_fraction:
        return ["%s: images differ (largest %d/255, %.3f %% of pixels)" % (what, diff.max(), 100 * fraction)]
    return []


def metadata(work, name):
    return pt.load_metadata(os.path.join(work, name + ".plenoptic.json"))


@pytest.fixture(scope="module")
def words(args):
    words = camera_words(args.build_dir)
    print("camera words read in context (%d): %s" % (len(words), " ".join(words)))
    return words


@pytest.fixture(scope="module")
def literal(args):
    literal, log_lit = render(args.povray, CAMERA_LITERAL, "camera-literal", args.work)
    assert literal is not None, "the literal camera does not render:\n" + log_lit[-1500:]
    return literal


def test_parser_table_has_the_known_words(words):
    missing = sorted(KNOWN_WORDS - set(words))
    assert not missing, "the parser's table lacks %s" % ", ".join("'%s'" % w for w in missing)


def test_camera_words_as_identifiers_render_as_with_debian(args, words):
    """1. Stock camera, camera words as identifiers: ours == Debian's."""
    reference = pt.require_debian_povray(args.reference_povray)
    scene = identifiers_scene(words)
    ours, log_ours = render(args.povray, scene, "identifiers", args.work)
    theirs, log_theirs = render(reference, scene, "identifiers-debian", args.work)
    assert theirs is not None, ("Debian's povray does not render the identifier scene (the test is wrong):\n"
                                + log_theirs[-1500:])
    assert ours is not None, "our povray does not render a scene that Debian's renders:\n" + log_ours[-1500:]
    # Identical up to the rounding our stock comparisons allow (tests/stock/test_stock_scenes.py).
    problems = compare(ours, theirs, "identifier scene, ours vs Debian's", max_diff=1, max_fraction=0.005)
    assert not problems, problems[0]
    assert float(ours.std()) >= 5, "the identifier scene rendered flat: the test scene shows nothing"


def test_identifiers_named_like_keywords_as_values(args, literal):
    """2. Identifiers named like keywords, used as values inside the camera."""
    named, log_named = render(args.povray, CAMERA_IDENTIFIERS, "camera-identifiers", args.work)
    assert named is not None, "the camera written with identifiers does not render:\n" + log_named[-1500:]
    problems = compare(literal, named, "camera with identifiers as values vs literal values")
    a, b = metadata(args.work, "camera-literal"), metadata(args.work, "camera-identifiers")
    for doc in (a, b):  # the microimage centres' file is named after the image
        if doc.get("microimages"):
            doc["microimages"].pop("file")
    for key in sorted((set(a) | set(b)) - {"depth_map", "virtual_depth_map"}):  # they name files
        if a.get(key) != b.get(key):
            problems.append("metadata '%s' differs: %s vs %s" % (key, a.get(key), b.get(key)))
    if not os.path.exists(os.path.join(args.work, "camera-identifiers.depth.exr")):
        problems.append("depth_map given as a keyword beside a declared 'depth_map' wrote no depth map")
    assert not problems, "\n".join(problems)


def test_block_words_declared_as_other_kinds_stay_keywords(args, literal):
    """3. Block words declared as other kinds of identifier still work as keywords."""
    other, log_other = render(args.povray, CAMERA_OTHER_KINDS, "camera-other-kinds", args.work)
    assert other is not None, ("the camera beside identifiers of other kinds does not render:\n"
                               + log_other[-1500:])
    problems = compare(literal, other, "camera beside identifiers of other kinds vs literal")
    assert not problems, problems[0]
