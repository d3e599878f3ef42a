# SPDX-License-Identifier: AGPL-3.0-or-later
"""Malformed plenoptic camera blocks: every one must be refused at parse time.

For each case the scene is written with one keyword per line (the layout of the example in
docs/specification.md, section 1) and the offending line marked with a `//!` comment. The
render must:
  - exit with a non-zero status, by itself (no signal, no time-out, no "Segmentation", no core);
  - print POV-Ray's parse error naming this file and the offending line
    (`File 'x.pov' line N: Parse Error: ...`; the old `File: x.pov  Line: N` form is accepted too);
  - say what is wrong: every expected fragment (the keyword, and the range or rule) in the message;
  - leave nothing behind: no image, no metadata JSON, no depth map, no render-state file.

Which line is "offending": a bad value is on the line of its keyword; a rule across several values
of one block (both or neither of two alternatives, a missing keyword) is checked at that block's
closing brace; a rule across blocks at the camera's closing brace. Both are what
docs/robustness.md promises the user.

Group "placement" holds NaN and infinite values in the placement keywords every POV-Ray camera
has (location, look_at, transforms); the specification (docs/specification.md, section 4)
refuses "any NaN or infinite value", while stock POV-Ray accepts them for its own cameras, so
they are a separate ctest.
"""
import os
import shutil

import pytest

import plenoptic_testing as pt

MAIN = """\
  main_lens {
    thin_lens
    focal_length 16
    f_number 4
    focus_distance 2
  }"""
ARRAY = """\
  microlens_array {
    hexagonal
    pitch 0.08
    focal_length 0.32
    distance 0.32
  }"""
SENSOR = """\
  sensor {
    pixel_size 0.01
  }"""
SAMPLES = "  samples 2"
MARK = "//!"


def camera(main=MAIN, array=ARRAY, sensor=SENSOR, extra=SAMPLES, close="}", head="", place=None):
    """A camera block from its parts; None leaves a part out."""
    lines = ["camera {", "  plenoptic"]
    lines += (place if place is not None else ["  location <0, 0.4, -2>", "  look_at <0, 0.3, 0>"])
    if head:
        lines.append(head)
    for part in (main, array, sensor, extra):
        if part is not None:
            lines.append(part)
    if close is not None:
        lines.append(close)
    return "\n".join(lines) + "\n"


def main_with(*body, close="  }"):
    return "\n".join(["  main_lens {"] + ["    " + b for b in body] + [close])


def array_with(*body, close="  }"):
    return "\n".join(["  microlens_array {"] + ["    " + b for b in body] + [close])


def sensor_with(*body, close="  }"):
    return "\n".join(["  sensor {"] + ["    " + b for b in body] + [close])


BRACE = "  }  " + MARK  # a block's closing brace, marked
CAMERA_BRACE = "}  " + MARK
THIN = ("thin_lens", "focal_length 16", "f_number 4", "focus_distance 2")
HEX = ("hexagonal", "pitch 0.08", "focal_length 0.32", "distance 0.32")


def refracting(surface="surface { radius 0.1 }", thickness="thickness 0.015", ior="ior 1.5", substrate="substrate 0.03",
               extra=(), close="}", head="lens {"):
    """A hexagonal array (pitch 0.08: corners 0.046 mm from the centre) of refracting microlenses,
    one keyword of lens { } per line; None leaves a line out."""
    body = [head] + ["  " + b for b in (surface, thickness, ior, substrate) + tuple(extra) if b is not None] + [close]
    return ("hexagonal", "pitch 0.08") + tuple(body) + ("distance 0.2",)

# (name, camera block, fragments the error message must contain, why it is refused)
CASES = [
    # ---- main_lens: values
    ("main focal_length negative", camera(main=main_with("thin_lens", "focal_length -16 " + MARK, "f_number 4", "focus_distance 2")),
     ["focal_length", "positive", "-16"], "lengths are positive"),
    ("main focal_length zero", camera(main=main_with("thin_lens", "focal_length 0 " + MARK, "f_number 4", "focus_distance 2")),
     ["focal_length", "positive", "got 0"], "lengths are positive"),
    ("main focal_length infinite", camera(main=main_with("thin_lens", "focal_length pow(10,400) " + MARK, "f_number 4", "focus_distance 2")),
     ["focal_length", "finite", "inf"], "no infinite value"),
    ("main focal_length NaN", camera(main=main_with("thin_lens", "focal_length pow(10,400)*0 " + MARK, "f_number 4", "focus_distance 2")),
     ["focal_length", "finite", "nan"], "no NaN"),
    ("main focal_length sqrt(-1)", camera(main=main_with("thin_lens", "focal_length sqrt(-1) " + MARK, "f_number 4", "focus_distance 2")),
     ["sqrt of negative number"], "POV-Ray's expression parser refuses it before the camera sees a NaN"),
    ("main focal_length a string", camera(main=main_with("thin_lens", 'focal_length "16" ' + MARK, "f_number 4", "focus_distance 2")),
     ["numeric expression"], "wrong type: a length is a number"),
    ("main focal_length a vector", camera(main=main_with("thin_lens", "focal_length <16, 16, 16>", "f_number 4 " + MARK, "focus_distance 2")),
     ["Float expected but vector"], "wrong type: a length is a number (POV-Ray's own type check notices at the next token)"),
    ("main focal_length without value", camera(main=main_with("thin_lens", "focal_length", "f_number 4 " + MARK, "focus_distance 2")),
     ["numeric expression"], "missing value (the next keyword is where POV-Ray notices)"),
    ("f_number zero", camera(main=main_with("thin_lens", "focal_length 16", "f_number 0 " + MARK, "focus_distance 2")),
     ["f_number", "positive", "got 0"], "f-numbers are positive"),
    ("f_number negative", camera(main=main_with("thin_lens", "focal_length 16", "f_number -4 " + MARK, "focus_distance 2")),
     ["f_number", "positive", "-4"], "f-numbers are positive"),
    ("aperture negative", camera(main=main_with("thin_lens", "focal_length 16", "aperture -1 " + MARK, "focus_distance 2")),
     ["aperture", "positive", "-1"], "lengths are positive"),
    ("main distance zero", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", "distance 0 " + MARK)),
     ["distance", "positive", "got 0"], "lengths are positive"),
    ("focus_distance negative", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", "focus_distance -2 " + MARK)),
     ["focus_distance", "positive", "-2"], "distances are positive"),
    ("focus_distance infinite", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", "focus_distance pow(10,400) " + MARK)),
     ["focus_distance", "finite", "inf"], "no infinite value (focus at infinity is distance = focal_length)"),
    # ---- main_lens: rules across its values (checked at its closing brace)
    ("main_lens thin_lens and pinhole", camera(main=main_with("thin_lens", "pinhole " + MARK, "distance 17", close=BRACE)),
     ["thin_lens", "pinhole"], "both alternatives: one kind of main lens (the later must not silently win)"),
    ("main_lens without type", camera(main=main_with("focal_length 16", "f_number 4", "focus_distance 2", close=BRACE)),
     ["main_lens", "thin_lens, pinhole, or a real lens"], "the block must say which lens it is"),
    ("thin_lens without focal_length", camera(main=main_with("thin_lens", "f_number 4", "focus_distance 2", close=BRACE)),
     ["focal_length"], "a thin lens needs F"),
    ("f_number and aperture both", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", "aperture 4", "focus_distance 2", close=BRACE)),
     ["f_number", "aperture", "not both"], "exactly one of the two"),
    ("neither f_number nor aperture", camera(main=main_with("thin_lens", "focal_length 16", "focus_distance 2", close=BRACE)),
     ["f_number", "aperture"], "exactly one of the two"),
    ("focus_distance and distance both", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", "focus_distance 2", "distance 17", close=BRACE)),
     ["focus_distance", "distance", "not both"], "one way to place the sensor"),
    ("neither focus_distance nor distance", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", close=BRACE)),
     ["focus_distance", "distance"], "the sensor must be placed"),
    ("focus inside the focal length", camera(main=main_with("thin_lens", "focal_length 16", "f_number 4", "focus_distance 0.01", close=BRACE)),
     ["focus_distance", "inside the focal length"], "no real image: 1/F = 1/z + 1/D has D < 0"),
    ("focus exactly at the focal length", camera(head="  mm_per_unit 1", main=main_with("thin_lens", "focal_length 16", "f_number 4", "focus_distance 16", close=BRACE)),
     ["focus_distance", "at or inside the focal length"], "D would be infinite"),
    ("pinhole with focal_length", camera(main=main_with("pinhole", "focal_length 16", "distance 17", close=BRACE), array=array_with(*HEX)),
     ["pinhole", "focal_length"], "a pinhole has no focal length"),
    ("pinhole with focus_distance", camera(main=main_with("pinhole", "focus_distance 2", close=BRACE)),
     ["pinhole", "focus_distance"], "a pinhole cannot focus"),
    ("pinhole without distance", camera(main=main_with("pinhole", close=BRACE)),
     ["pinhole", "distance"], "the sensor must be placed"),
    ("unknown keyword in main_lens", camera(main=main_with(*THIN, "bokeh_blades 6 " + MARK)),
     ["bokeh_blades", "main_lens keyword", "allowed"], "unknown keywords are errors, never ignored"),
    ("reserved word in main_lens", camera(main=main_with(*THIN, "radius 3 " + MARK)),
     ["radius", "main_lens keyword"], "unknown keywords are errors, never ignored"),
    ("main_lens unterminated", camera(main=main_with(*THIN, close=""), array=array_with(*HEX).replace("  microlens_array {", "  microlens_array {  " + MARK, 1)),
     ["microlens_array", "main_lens keyword"], "a missing brace is noticed at the next block's keyword"),
    # ---- microlens_array
    ("pitch negative", camera(array=array_with("hexagonal", "pitch -0.08 " + MARK, "focal_length 0.32", "distance 0.32")),
     ["pitch", "positive", "-0.08"], "lengths are positive"),
    ("pitch zero", camera(array=array_with("hexagonal", "pitch 0 " + MARK, "focal_length 0.32", "distance 0.32")),
     ["pitch", "positive", "got 0"], "lengths are positive"),
    ("pitch NaN", camera(array=array_with("hexagonal", "pitch pow(-8, 1/3) " + MARK, "focal_length 0.32", "distance 0.32")),
     ["pitch", "finite", "nan"], "no NaN"),
    ("pitch missing", camera(array=array_with("hexagonal", "focal_length 0.32", "distance 0.32", close=BRACE)),
     ["pitch"], "the lattice needs a spacing"),
    ("array without grid", camera(array=array_with("pitch 0.08", "focal_length 0.32", "distance 0.32", close=BRACE)),
     ["rectangular or hexagonal"], "the block must say which lattice"),
    ("array without lens", camera(array=array_with("hexagonal", "pitch 0.08", "distance 0.32", close=BRACE)),
     ["focal_length", "pinhole"], "the block must say which lenses"),
    ("array focal_length then pinhole", camera(array=array_with("hexagonal", "pitch 0.08", "focal_length 0.32", "pinhole " + MARK, "distance 0.32", close=BRACE)),
     ["pinhole", "focal_length", "not"], "both alternatives: one kind of lens (the later must not silently win)"),
    ("array pinhole then focal_length", camera(array=array_with("hexagonal", "pitch 0.08", "pinhole", "focal_length 0.32 " + MARK, "distance 0.32", close=BRACE)),
     ["pinhole", "focal_length", "not"], "both alternatives: one kind of lens (the later must not silently win)"),
    ("array focal_length and focal_lengths", camera(array=array_with("hexagonal", "pitch 0.08", "focal_length 0.32", "focal_lengths <0.3, 0.32, 0.34> " + MARK, "distance 0.32", close=BRACE)),
     ["focal_length", "focal_lengths"], "both alternatives: one lens type or three"),
    ("array hexagonal and rectangular", camera(array=array_with("hexagonal", "rectangular " + MARK, "pitch 0.08", "focal_length 0.32", "distance 0.32", close=BRACE)),
     ["hexagonal", "rectangular"], "both alternatives: one lattice"),
    ("focal_lengths on a rectangular grid", camera(array=array_with("rectangular", "pitch 0.08", "focal_lengths <0.3, 0.32, 0.34>", "distance 0.32", close=BRACE)),
     ["focal_lengths", "hexagonal"], "three interleaved types need the hexagonal lattice"),
    ("focal_lengths with a negative value", camera(array=array_with("hexagonal", "pitch 0.08", "focal_lengths <0.3, -0.32, 0.34> " + MARK, "distance 0.32")),
     ["focal_lengths", "positive", "-0.32"], "lengths are positive"),
    ("focal_lengths with NaN", camera(array=array_with("hexagonal", "pitch 0.08", "focal_lengths <0.3, mod(1, 0), 0.34> " + MARK, "distance 0.32")),
     ["focal_lengths", "finite", "nan"], "no NaN"),
    ("array focal_length infinite", camera(array=array_with("hexagonal", "pitch 0.08", "focal_length 1e400 " + MARK, "distance 0.32")),
     ["focal_length", "finite", "inf"], "no infinite value"),
    ("array distance missing", camera(array=array_with("hexagonal", "pitch 0.08", "focal_length 0.32", close=BRACE)),
     ["distance"], "the sensor must be placed"),
    ("array distance negative", camera(array=array_with("hexagonal", "pitch 0.08", "focal_length 0.32", "distance -0.32 " + MARK)),
     ["distance", "positive", "-0.32"], "lengths are positive"),
    ("array rotate infinite", camera(array=array_with(*HEX, "rotate <pow(10,400), 0, 0> " + MARK)),
     ["rotate", "finite", "inf"], "no infinite value"),
    ("array translate NaN", camera(array=array_with(*HEX, "translate <0, pow(10,400)*0, 0> " + MARK)),
     ["translate", "finite", "nan"], "no NaN"),
    ("unknown keyword in microlens_array", camera(array=array_with(*HEX, "spacing 0.1 " + MARK)),
     ["spacing", "microlens_array keyword", "allowed"], "unknown keywords are errors, never ignored"),
    ("microlens_array unterminated", camera(array=array_with(*HEX, close=""), sensor=SENSOR.replace("  sensor {", "  sensor {  " + MARK, 1)),
     ["sensor", "microlens_array keyword"], "a missing brace is noticed at the next block's keyword"),
    # ---- sensor
    ("pixel_size zero", camera(sensor=sensor_with("pixel_size 0 " + MARK)),
     ["pixel_size", "positive", "got 0"], "lengths are positive"),
    ("pixel_size negative component", camera(sensor=sensor_with("pixel_size <0.01, -0.01> " + MARK)),
     ["pixel_size", "positive", "-0.01"], "lengths are positive"),
    ("pixel_size infinite component", camera(sensor=sensor_with("pixel_size <0.01, pow(10,400)> " + MARK)),
     ["pixel_size", "finite", "inf"], "no infinite value"),
    ("sensor offset NaN", camera(sensor=sensor_with("pixel_size 0.01", "offset <pow(10,400)*0, 0> " + MARK)),
     ["offset", "finite", "nan"], "no NaN"),
    # ---- sensor: the read-out to the raw (docs/sensor.md)
    ("bayer unknown pattern", camera(sensor=sensor_with("pixel_size 0.01", "bayer rgbg " + MARK)),
     ["bayer", "rggb, bggr, grbg, gbrg", "rgbg"], "only the four Bayer patterns"),
    ("bayer a string", camera(sensor=sensor_with("pixel_size 0.01", 'bayer "rggb" ' + MARK)),
     ["bayer", "rggb, bggr, grbg, gbrg"], "the pattern is a word, not a string"),
    ("bit_depth 17", camera(sensor=sensor_with("pixel_size 0.01", "bit_depth 17 " + MARK)),
     ["bit_depth", "1 to 16", "17"], "the raw is a 16-bit PNG"),
    ("bit_depth fractional", camera(sensor=sensor_with("pixel_size 0.01", "bit_depth 10.5 " + MARK)),
     ["bit_depth", "whole number", "10.5"], "bits are whole"),
    ("full_well zero", camera(sensor=sensor_with("pixel_size 0.01", "full_well 0 " + MARK)),
     ["full_well", "positive", "got 0"], "a well holds electrons"),
    ("exposure negative", camera(sensor=sensor_with("pixel_size 0.01", "exposure -100 " + MARK)),
     ["exposure", "positive", "-100"], "an exposure collects electrons"),
    ("read_noise negative", camera(sensor=sensor_with("pixel_size 0.01", "read_noise -2 " + MARK)),
     ["read_noise", "from 0", "-2"], "an rms is not negative"),
    ("prnu NaN", camera(sensor=sensor_with("pixel_size 0.01", "prnu pow(10,400)*0 " + MARK)),
     ["prnu", "finite", "nan"], "no NaN"),
    ("seed fractional", camera(sensor=sensor_with("pixel_size 0.01", "seed 2.5 " + MARK)),
     ["seed", "whole number", "2.5"], "a seed is a whole number"),
    ("black_level above the range", camera(sensor=sensor_with("pixel_size 0.01", "bit_depth 8", "black_level 255", close=BRACE)),
     ["black_level", "0 to 254", "255"], "the black level lies below the largest DN (checked at the brace: it needs bit_depth)"),
    ("white_image f_numbers zero", camera(extra=SAMPLES + "\n  white_image f_numbers <2, 0> " + MARK),
     ["white_image f_numbers", "0"], "an f-number is positive"),
    ("white_image f_numbers with a pinhole main lens",
     camera(main=main_with("pinhole", "distance 17"), extra=SAMPLES + "\n  white_image f_numbers 4", close=CAMERA_BRACE),
     ["white_image", "f_numbers", "pinhole"], "a pinhole has no aperture to change (checked at the camera's brace)"),
    ("radiometry unknown model", camera(extra=SAMPLES + "\n  radiometry physical " + MARK),
     ["radiometry", "flat, irradiance", "physical"], "only the two radiometries"),
    ("radiometry a string", camera(extra=SAMPLES + '\n  radiometry "irradiance" ' + MARK),
     ["radiometry", "flat, irradiance"], "the model is a word, not a string"),
    ("radiometry irradiance behind a pinhole main lens with lenslets",
     camera(main=main_with("pinhole", "distance 17"), extra=SAMPLES + "\n  radiometry irradiance", close=CAMERA_BRACE),
     ["radiometry irradiance", "pinhole", "radiometry flat"],
     "each lenslet would focus the pinhole's light to a point (checked at the camera's brace)"),
    ("angular_response negative", camera(sensor=sensor_with("pixel_size 0.01", "angular_response -1 " + MARK)),
     ["angular_response", "from 0 to 64", "-1"], "an exponent of cos^n, not negative"),
    ("angular_response under flat radiometry", camera(sensor=sensor_with("pixel_size 0.01", "angular_response 8"),
                                                      close=CAMERA_BRACE),
     ["angular_response", "radiometry irradiance"], "the stock cameras' picture has no angular response (checked at the camera's brace)"),
    ("diffraction wavelength zero", camera(extra=SAMPLES + "\n  diffraction wavelengths <610, 0, 465> " + MARK),
     ["diffraction wavelengths", "nanometres", "from 100 to 20000", "got 0"], "a wavelength is positive, in nm"),
    ("diffraction wavelength NaN", camera(extra=SAMPLES + "\n  diffraction wavelengths <610, pow(10,400)*0, 465> " + MARK),
     ["diffraction wavelengths", "finite", "nan"], "no NaN"),
    ("diffraction behind pinhole microlenses",
     camera(array=array_with("hexagonal", "pitch 0.08", "pinhole", "distance 0.32"), extra=SAMPLES + "\n  diffraction",
            close=CAMERA_BRACE),
     ["diffraction", "pinhole microlenses", "focal_length"], "a point has no Airy pattern (checked at the camera's brace)"),
    ("unknown keyword in sensor", camera(sensor=sensor_with("pixel_size 0.01", "resolution 640 " + MARK)),
     ["resolution", "sensor keyword", "allowed"], "unknown keywords are errors, never ignored"),
    ("sensor unterminated", camera(sensor=sensor_with("pixel_size 0.01", close=""), extra="  samples 2  " + MARK),
     ["samples", "sensor keyword"], "a missing brace is noticed at the next keyword"),
    # ---- spectral sampling (docs/spectral.md)
    ("spectral zero bands", camera(extra=SAMPLES + "\n  spectral 0 " + MARK),
     ["spectral", "whole number", "1 to 64", "got 0"], "at least one band"),
    ("spectral fractional bands", camera(extra=SAMPLES + "\n  spectral 2.5 " + MARK),
     ["spectral", "whole number", "2.5"], "bands are counted"),
    ("spectral too many bands", camera(extra=SAMPLES + "\n  spectral 65 " + MARK),
     ["spectral", "1 to 64", "65"], "at most 64 bands"),
    ("spectral response width too narrow", camera(extra=SAMPLES + "\n  spectral 8 response_widths <90, 0.5, 90> " + MARK),
     ["spectral response_widths", "1 to 1000", "0.5"], "a Gaussian of a fraction of a nanometre is no colour filter"),
    ("spectral response centre out of range", camera(extra=SAMPLES + "\n  spectral 8 response_centres <610, 50, 465> " + MARK),
     ["spectral response_centres", "100 to 20000", "got 50"], "a wavelength in nm"),
    ("spectral response far from the visible", camera(extra=SAMPLES + "\n  spectral 8 response_centres <610, 550, 5000> "
                                                             "response_widths <90, 90, 20>", close=CAMERA_BRACE),
     ["b channel responds to no wavelength", "380", "720"], "a channel that sees none of the traced light cannot be weighed"),
    ("spectral response_file missing", camera(extra=SAMPLES + '\n  spectral 8 response_file "no_such_response.csv" ' + MARK),
     ["response_file", "no_such_response.csv", "not found"], "the table must exist"),

    # ---- microlens arrays with errors, fill factors, masks (docs/camera.md, "Real microlens arrays")
    ("errors position too large", camera(array=array_with(*HEX, "errors {", "  position 0.004", "  seed 1", "}", close=BRACE)),
     ["errors position", "0.004", "must be below", "quarter"], "a lens is found from its cell and its neighbours only within a quarter pitch"),
    ("errors position negative", camera(array=array_with(*HEX, "errors {", "  position -0.001 " + MARK, "}")),
     ["errors position", "-0.001", "zero or positive"], "a standard deviation"),
    ("errors S_z negative", camera(array=array_with(*HEX, "errors {", "  position 0.001, -0.001 " + MARK, "}")),
     ["errors position", "-0.001", "zero or positive"], "a standard deviation"),
    ("errors focal_length too large", camera(array=array_with(*HEX, "errors {", "  focal_length 0.2", "}", close=BRACE)),
     ["errors focal_length", "0.2", "below 0.05"], "no focal length may come near zero"),
    ("errors rotation 45", camera(array=array_with(*HEX, "errors {", "  rotation 45 " + MARK, "}")),
     ["errors rotation", "45", "[0, 30)"], "a tilt is a small error"),
    ("errors seed fractional", camera(array=array_with(*HEX, "errors {", "  seed 1.5 " + MARK, "}")),
     ["seed", "1.5"], "a seed is a whole number"),
    ("errors unknown keyword", camera(array=array_with(*HEX, "errors {", "  jitter 0.001 " + MARK, "}")),
     ["jitter", "allowed", "position", "focal_length", "rotation", "seed"], "unknown keywords are errors"),
    ("errors focal_length with pinholes", camera(array=array_with("hexagonal", "pitch 0.08", "pinhole", "distance 0.32", "errors {", "  focal_length 0.01", "}", close=BRACE)),
     ["errors focal_length and rotation", "pinholes", "position only"], "a pinhole has no focal length"),
    ("errors and lens_table", camera(array=array_with(*HEX, "errors { position 0.001 }", 'lens_table "t.csv" ' + MARK)),
     ["errors { } or lens_table"], "one source of errors"),
    ("lens_table missing", camera(array=array_with(*HEX, 'lens_table "no_such_table.csv" ' + MARK)),
     ["lens_table", "no_such_table.csv", "not found"], "the table must exist"),
    ("fill_factor zero", camera(array=array_with(*HEX, "fill_factor 0 " + MARK)),
     ["fill_factor", "(0, 1]", "0"], "some of each cell must be lens"),
    ("fill_factor above 1", camera(array=array_with(*HEX, "fill_factor 1.2 " + MARK)),
     ["fill_factor", "(0, 1]", "1.2"], "a share of the cell"),
    ("fill_factor with pinholes", camera(array=array_with("hexagonal", "pitch 0.08", "pinhole", "distance 0.32", "fill_factor 0.8", close=BRACE)),
     ["fill_factor and mask", "pinhole"], "a pinhole passes light at its centre only"),

    # ---- camera level: sampling, scale, unknown keywords, rules across blocks
    ("samples 0", camera(extra="  samples 0  " + MARK),
     ["samples", "whole number", "got 0"], "at least one ray per pixel"),
    ("samples 0.5", camera(extra="  samples 0.5  " + MARK),
     ["samples", "whole number", "0.5"], "a count is a whole number"),
    ("samples -3", camera(extra="  samples -3  " + MARK),
     ["samples", "whole number", "-3"], "at least one ray per pixel"),
    ("samples infinite", camera(extra="  samples pow(10,400)  " + MARK),
     ["samples", "inf"], "no infinite value"),
    ("samples above the maximum", camera(extra="  samples 2000000  " + MARK),
     ["samples", "1000000", "2000000"], "bounded work per pixel"),
    ("adaptive minimum above maximum", camera(extra="  samples 16, 4  " + MARK),
     ["samples", "minimum", "maximum"], "min <= max"),
    ("adaptive maximum 0.5", camera(extra="  samples 4, 0.5  " + MARK),
     ["samples", "whole number", "0.5"], "a count is a whole number"),
    ("confidence 1.5", camera(extra="  samples 4, 16\n  confidence 1.5  " + MARK),
     ["confidence", "between 0 and 1", "1.5"], "a probability"),
    ("confidence 0", camera(extra="  samples 4, 16\n  confidence 0  " + MARK),
     ["confidence", "between 0 and 1", "got 0"], "a probability strictly inside (0, 1)"),
    ("microimage_error_anchors 3.5", camera(extra="  microimage_error_anchors 3.5  " + MARK),
     ["microimage_error_anchors", "0 (every lens measured)", "4 to 4096", "3.5"],
     "a spacing of whole lenses, at least the 4 the anchors' differences need"),
    ("variance negative", camera(extra="  samples 4, 16\n  variance -1  " + MARK),
     ["variance", "positive", "-1"], "a variance is positive"),
    ("mm_per_unit zero", camera(head="  mm_per_unit 0  " + MARK),
     ["mm_per_unit", "positive", "got 0"], "a scale is positive"),
    ("mm_per_unit negative", camera(head="  mm_per_unit -1000  " + MARK),
     ["mm_per_unit", "positive", "-1000"], "a scale is positive"),
    ("mm_per_unit infinite", camera(head="  mm_per_unit pow(10,400)  " + MARK),
     ["mm_per_unit", "finite", "inf"], "no infinite value"),
    ("unknown keyword in camera", camera(extra="  samples 2\n  exposure 2  " + MARK),
     ["exposure", "plenoptic camera keyword", "allowed"], "unknown keywords are errors, never ignored"),
    ("focal_blur aperture in camera", camera(extra="  samples 2\n  aperture 0.5  " + MARK),
     ["aperture", "does not apply"], "focal blur would silently mean nothing"),
    ("angle in camera", camera(extra="  samples 2\n  angle 40  " + MARK),
     ["angle", "does not apply"], "the field of view comes from the optics"),
    ("neither main_lens nor array", camera(main=None, array=None, close=CAMERA_BRACE),
     ["main_lens", "microlens_array"], "nothing to image with"),
    ("pinhole main lens with pinhole array", camera(main=main_with("pinhole", "distance 17"), array=array_with("hexagonal", "pitch 0.08", "pinhole", "distance 0.32"), close=CAMERA_BRACE),
     ["pinhole", "degenerate"], "no ray passes two points and a pixel"),
    ("pinhole main lens imaging the sensor onto the pinhole", camera(main=main_with("pinhole", "distance 2"), array=array_with("rectangular", "pitch 0.08", "focal_length 1", "distance 2"), close=CAMERA_BRACE),
     ["degenerate", "1/D + 1/d = 1/f"], "1/D + 1/d = 1/f sends every ray back to its sensor point"),
    ("array tilted edge-on", camera(array=array_with(*HEX, "rotate <90, 0, 0>"), close=CAMERA_BRACE),
     ["rotate", "edge-on"], "an edge-on array passes no light"),
    ("array translated behind the sensor", camera(array=array_with(*HEX, "translate <0, 0, -0.5>"), close=CAMERA_BRACE),
     ["translate", "behind the sensor"], "the array must lie between lens and sensor"),
    ("array translated in front of the main lens", camera(array=array_with(*HEX, "translate <0, 0, 30>"), close=CAMERA_BRACE),
     ["translate", "main lens"], "the array must lie between lens and sensor"),
    # The adaptive form's variance test needs two samples to start from.
    ("adaptive samples with a minimum of 1", camera(extra="  samples 1, 64  " + MARK),
     ["samples", "at least 2", "samples N"], "one sample has no variance: the pixel would stop after one ray"),
    ("camera unterminated", camera(close=None),
     ["light_source", "plenoptic camera keyword"], "a missing brace is noticed at the next statement (no marker: the world's first line)"),
]

# NaN / infinity in the placement keywords every camera has (stock POV-Ray accepts them).
PLACEMENT_CASES = [
    ("location NaN", camera(place=["  location <0, pow(10,400)*0, -2>  " + MARK, "  look_at <0, 0.3, 0>"]),
     ["location"], "no NaN: every ray would start nowhere"),
    ("location infinite", camera(place=["  location <0, pow(10,400), -2>  " + MARK, "  look_at <0, 0.3, 0>"]),
     ["location"], "no infinite value"),
    ("look_at NaN", camera(place=["  location <0, 0.4, -2>", "  look_at <mod(1, 0), 0.3, 0>  " + MARK]),
     ["look_at"], "no NaN"),
    ("camera rotate NaN", camera(extra="  samples 2\n  rotate <pow(10,400)*0, 0, 0>  " + MARK),
     ["rotate"], "no NaN"),
    ("camera translate infinite", camera(extra="  samples 2\n  translate <pow(10,400), 0, 0>  " + MARK),
     ["translate"], "no infinite value"),
    # A degenerate frame once wrote metadata the project's own reader refused.
    ("right zero", camera(place=["  location <0, 0.4, -2>", "  right 0  " + MARK]),
     ["right", "zero"], "no frame without a right vector"),
    ("up zero", camera(place=["  location <0, 0.4, -2>", "  up 0  " + MARK]),
     ["up", "zero"], "no frame without an up vector"),
    ("direction zero", camera(place=["  location <0, 0.4, -2>", "  direction 0  " + MARK]),
     ["direction", "zero"], "no frame without a viewing direction"),
    ("right parallel to up", camera(place=["  location <0, 0.4, -2>", "  right y", "  up y  " + MARK]),
     ["right, up and direction", "parallel", "after 'up'"], "the frame must span 3-D space"),
    ("direction in the plane of right and up", camera(place=["  location <0, 0.4, -2>", "  direction <1, 1, 0>  " + MARK]),
     ["right, up and direction", "span 3-D space"], "the frame must span 3-D space"),
    ("right parallel to direction", camera(place=["  location <0, 0.4, -2>", "  direction z", "  right <0, 0, 2>  " + MARK]),
     ["parallel or lie in one plane", "after 'right'"], "the frame must span 3-D space"),
]

# Real main lenses: the refusals of a prescription, written inline so the scene is
# self-contained (a lens file's rows are refused the same way, naming the file and its row).
S1 = "  surface { radius 30 thickness 5 ior 1.5 aperture 20 }"
S2 = "  surface { radius -30 thickness 0 ior 1 aperture 20 }"
STOP = "  stop { thickness 2 aperture 8 }"
REAL = ("prescription {", STOP, S1, S2, "}")
REAL_LENS_CASES = [
    ("prescription without a stop", camera(main=main_with("prescription {", S1, S2, "}  " + MARK, "focus_distance 2")),
     ["no aperture stop"], "a lens has exactly one stop"),
    ("prescription with two stops", camera(main=main_with("prescription {", STOP, S1, STOP + "  " + MARK, S2, "}", "focus_distance 2")),
     ["two aperture stops"], "a lens has exactly one stop"),
    ("surface aperture zero", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 5 ior 1.5 aperture 0 }  " + MARK, S2, "}", "focus_distance 2")),
     ["surface aperture", "positive"], "a clear aperture is a positive diameter"),
    ("surface aperture beyond its sphere", camera(main=main_with("prescription {", STOP, "  surface { radius 5 thickness 5 ior 1.5 aperture 12 }  " + MARK, S2, "}", "focus_distance 2")),
     ["exceeds", "sphere"], "a clear aperture cannot exceed its sphere"),
    ("surface without ior", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 5 aperture 20 }  " + MARK, S2, "}", "focus_distance 2")),
     ["surface needs", "ior"], "every number of a row is required"),
    ("real lens cannot focus", camera(main=main_with(*(REAL + ("focus_distance 0.01",)), close=BRACE)),
     ["cannot focus", "front focal point"], "an object inside the front focal length has no real image"),
    ("lens_file not found", camera(main=main_with('lens_file "no-such-lens.dat"  ' + MARK, "focus_distance 2")),
     ["lens_file", "not found"], "a missing file is named"),
    ("thin_lens with a prescription", camera(main=main_with("thin_lens", *(REAL + ("focus_distance 2",)), close=BRACE)),
     ["thin_lens", "thick_lens"], "a thin lens has no surfaces; the error says what to write instead"),
    ("focal_length with a prescription", camera(main=main_with("focal_length 50", *(REAL + ("focus_distance 2",)), close=BRACE)),
     ["focal_length", "real lens"], "a real lens's focal length follows from its surfaces"),
    ("blades two", camera(main=main_with(*(REAL + ("blades 2  " + MARK, "focus_distance 2")))),
     ["blades", "3"], "an iris has at least three blades"),
    ("thick_lens with blades", camera(main=main_with("thick_lens", *(REAL + ("blades 6", "focus_distance 2")), close=BRACE)),
     ["thick_lens", "blades"], "the paraxial equivalent has a round pupil"),
    ("thick_lens without a lens", camera(main=main_with("thick_lens", "focus_distance 2", close=BRACE)),
     ["thick_lens", "lens_file"], "the paraxial equivalent of what?"),
    # A biconcave singlet R1 = -30, R2 = 30, n = 1.5, 2 mm thick: 1/f = (n - 1) [1/R1 - 1/R2 +
    # (n - 1) t / (n R1 R2)] gives f = -29.67 mm.
    ("diverging lens", camera(main=main_with("prescription {", STOP, "  surface { radius -30 thickness 2 ior 1.5 aperture 20 }",
                                             "  surface { radius 30 thickness 0 ior 1 aperture 20 }", "}  " + MARK, "distance 50")),
     ["prescription", "negative focal length", "effective focal length is -29.67", "relay", "positive focal length"],
     "a plenoptic main lens must form a real image"),
    # R = +-30 over 20 mm: each sag at the rim is 30 - sqrt(800) = 1.72 mm, so a 0.5 mm thick
    # element crosses itself where 30 - sqrt(900 - h^2) = 0.25: h = 3.865 mm.
    ("surfaces that cross", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 0.5 ior 1.5 aperture 20 }  " + MARK,
                                                  S2, "}", "focus_distance 2")),
     ["surface 2", "surface 3", "cross", "meet 3.8649", "smaller clear aperture"], "glass cannot pass through glass"),
    # Dispersion (docs/real-lenses.md, "Dispersion"): refused at the row's line, naming the value and the range.
    ("surface abbe out of range", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 5 ior 1.5 aperture 20 abbe 2 }  " + MARK,
                                                        S2, "}", "focus_distance 2")),
     ["surface abbe", "V_d 2", "5 to 150"], "an index or a slip in the Abbe number's place"),
    ("abbe on air", camera(main=main_with("prescription {", STOP, S1, "  surface { radius -30 thickness 0 ior 1 aperture 20 abbe 30 }  " + MARK,
                                          "}", "focus_distance 2")),
     ["surface 3", "air (index 1)", "does not disperse"], "air's index stays 1"),
    ("sellmeier with five numbers", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 5 ior 1.5168 aperture 20 "
                                                          "sellmeier <1.04, 0.23, 1.01, 0.006, 0.02> }  " + MARK, S2, "}", "focus_distance 2")),
     ["surface sellmeier", "six numbers", "found 5"], "B1..B3 and C1..C3"),
    ("sellmeier resonance in the visible", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 5 ior 1.5168 aperture 20 "
                                                                 "sellmeier <1.03961212, 0.231792344, 1.01046945, 0.00600069867, 0.25, 103.560653> }  " + MARK,
                                                                 S2, "}", "focus_distance 2")),
     ["surface 2", "C2 = 0.25", "resonance at 500 nm", "380 to 720"], "a pole of the index where the render traces"),
    ("sellmeier and abbe", camera(main=main_with("prescription {", STOP, "  surface { radius 30 thickness 5 ior 1.5168 aperture 20 abbe 64 "
                                                 "sellmeier <1.03961212, 0.231792344, 1.01046945, 0.00600069867, 0.0200179144, 103.560653> }  " + MARK,
                                                 S2, "}", "focus_distance 2")),
     ["surface 2", "not both"], "one model per medium"),
    ("microlens abbe on pinholes", camera(array=array_with("hexagonal", "pitch 0.08", "pinhole", "abbe 40", "distance 0.32", close=BRACE)),
     ["microlens_array abbe 40", "pinhole"], "a pinhole has no glass"),
    ("microlens abbe out of range", camera(array=array_with(*HEX, "abbe 200  " + MARK)),
     ["microlens_array abbe", "200", "5 to 150"], "an Abbe number no glass has"),
    # ---- microlens_array { lens { } }: refracting microlenses
    ("refracting cap narrower than its cell", camera(array=array_with(*refracting(surface="surface { radius 0.04 }"), close=BRACE)),
     ["microlens_array lens surface radius 0.04", "does not cover the lens's cell", "0.046", "hexagonal pitch 0.08"],
     "the cap's clear aperture is its whole cell"),
    ("refracting conic narrows the cap", camera(array=array_with(*refracting(surface="surface { radius 0.1 conic 4 }"), close=BRACE)),
     ["radius 0.1", "conic 4", "does not cover"], "an oblate cap ends at R / sqrt(1 + k)"),
    ("refracting cap taller than its thickness", camera(array=array_with(*refracting(thickness="thickness 0.005"), close=BRACE)),
     ["cap rises", "more than its thickness 0.005"], "the cap's sag over its cell must fit in t"),
    ("refracting ior 1", camera(array=array_with(*refracting(ior="ior 1  " + MARK))),
     ["microlens_array lens ior", "greater than 1", "got 1"], "no power without glass"),
    ("refracting ior NaN", camera(array=array_with(*refracting(ior="ior pow(-8, 1/3)  " + MARK))),
     ["microlens_array lens ior", "finite", "nan"], "no NaN"),
    ("refracting substrate negative", camera(array=array_with(*refracting(substrate="substrate -0.03  " + MARK))),
     ["microlens_array lens substrate", "positive", "-0.03"], "lengths are positive"),
    ("refracting radius zero", camera(array=array_with(*refracting(surface="surface { radius 0 }  " + MARK))),
     ["microlens_array lens surface radius", "positive", "got 0"], "a cap has a curvature"),
    ("refracting conic out of range", camera(array=array_with(*refracting(surface="surface { radius 0.1 conic 1000 }  " + MARK))),
     ["microlens_array lens surface conic", "-100 to 100", "1000"], "the conic's range"),
    ("refracting without substrate", camera(array=array_with(*refracting(substrate=None, close="}  " + MARK))),
     ["microlens_array lens needs", "substrate"], "every dimension of the lens is given"),
    ("refracting surface without radius", camera(array=array_with(*refracting(surface="surface { conic -1 }  " + MARK))),
     ["microlens_array lens surface needs radius"], "the cap's radius is required"),
    ("refracting two surfaces", camera(array=array_with(*refracting(extra=("surface { radius 0.2 }  " + MARK,)))),
     ["one surface"], "the lens is plano-convex: one curved surface"),
    ("refracting curved_side unknown", camera(array=array_with(*refracting(extra=("curved_side up  " + MARK,)))),
     ["curved_side", "scene", "sensor"], "the side is one of two words"),
    ("refracting unknown keyword", camera(array=array_with(*refracting(extra=("focal_length 0.2  " + MARK,)))),
     ["focal_length", "microlens_array lens keyword", "allowed"], "unknown keywords are errors, never ignored"),
    ("refracting with focal_length", camera(array=array_with("focal_length 0.2", *refracting(head="lens {  " + MARK))),
     ["lens { }", "not several"], "one kind of microlens"),
    ("refracting cap shrunk by focal-length errors", camera(array=array_with(*refracting(surface="surface { radius 0.054 }",
                                                                                     thickness="thickness 0.03"),
                                                                           "errors { focal_length 0.04 }", close=BRACE)),
     ["microlens_array errors focal_length 0.04", "0.84 times the cap's focal length", "does not cover the lens's cell",
      "0.046"],
     "every drawn lens's cap (radius scaled with its focal length, to 4 standard deviations) must fit its cell"),
    ("refracting with a fill factor", camera(array=array_with(*refracting(), "fill_factor 0.8", close=BRACE)),
     ["fill_factor", "not modelled for refracting microlenses"], "the caps fill their cells"),
    ("refracting behind a pinhole main lens", camera(main=main_with("pinhole", "distance 17"), array=array_with(*refracting()),
                                                     close=CAMERA_BRACE),
     ["pinhole main_lens with refracting microlenses", "not supported"], "no closed form for the one ray through a pinhole"),
]

GROUPS = {"camera": CASES, "placement": PLACEMENT_CASES, "real_lens": REAL_LENS_CASES}


def marked_lines(block):
    """Lines (1-based, in the whole scene) where the error may be reported: every line marked
    with MARK (a rule may be checked at the second keyword or at the closing brace); a block
    without a marker is unterminated, and the error belongs at the first line after it."""
    text = pt.scene_text(block).splitlines()
    marked = [n for n, line in enumerate(text, 1) if MARK in line]
    if marked:
        return marked
    return [len(pt.WORLD_HEADER.splitlines()) + len(block.rstrip("\n").splitlines()) + 1]


def check_case(povray, work, index, name, block, fragments):
    """Problems found (an empty list when the refusal is as promised)."""
    case_dir = os.path.join(work, "case%02d" % index)
    shutil.rmtree(case_dir, ignore_errors=True)
    os.makedirs(case_dir)
    scene = os.path.join(case_dir, "bad.pov")
    pt.write_scene(scene, block)
    expected_lines = marked_lines(block)
    run = pt.run_povray(povray, "bad.pov", os.path.join(case_dir, "bad.png"), 16, 12,
                           ["+FN8", "+WT1"], timeout=30, cwd=case_dir)
    problems, err = pt.refusal_problems(run)
    if err is not None:
        efile, eline, message = err
        if os.path.basename(efile) != "bad.pov":
            problems.append("error names file %r, expected bad.pov" % efile)
        if eline not in expected_lines:
            text = pt.scene_text(block).splitlines()
            problems.append("LINE: error reported at line %d (%r), expected line %s (%s)" %
                            (eline, text[eline - 1].strip() if 0 < eline <= len(text) else "?",
                             " or ".join(str(n) for n in expected_lines),
                             " / ".join(repr(text[n - 1].strip()) for n in expected_lines)))
        missing = [frag for frag in fragments if frag.lower() not in message.lower()]
        if missing:
            problems.append("message lacks %s: %r" % (", ".join(repr(m) for m in missing), message))
    left = sorted(f for f in os.listdir(case_dir) if f not in ("bad.pov",))
    if left:
        problems.append("left files behind: %s" % ", ".join(left))
    if problems and all(p.startswith("LINE:") for p in problems):
        problems.append("message (right apart from the line): " + err[2])
    elif problems:
        problems.append("povray output:\n" + pt.tail(run.output, 8))
    return problems, run, err


def refused(args, group, index, name, block, fragments, why):
    work = os.path.join(args.work, group)
    os.makedirs(work, exist_ok=True)
    problems, run, err = check_case(args.povray, work, index, name, block, fragments)
    note = ""
    if problems and problems[0].startswith("LINE:"):
        note = ("\nNOTE: only the reported line is wrong: the value was refused with the right message, but at "
                "the line of the token after it (the check runs once POV-Ray has read ahead; known bug, see "
                "docs/robustness.md)")
    assert not problems, "%s (%s)\n     %s%s" % (name, why, "\n     ".join(problems), note)
    print("ok   %-50s line %d: %s" % (name, err[1], err[2][:110]))


@pytest.mark.parametrize("index", range(len(CASES)), ids=[c[0] for c in CASES])
def test_camera_block(args, index):
    """ctest robustness_malformed_cameras (with test_camera_table_size)."""
    refused(args, "camera", index, *CASES[index])


def test_camera_table_size():
    assert len(CASES) >= 40, "the table must hold at least 40 cases, it has %d" % len(CASES)


@pytest.mark.parametrize("index", range(len(PLACEMENT_CASES)), ids=[c[0] for c in PLACEMENT_CASES])
def test_placement_keyword(args, index):
    """ctest robustness_malformed_placement."""
    refused(args, "placement", index, *PLACEMENT_CASES[index])


@pytest.mark.parametrize("index", range(len(REAL_LENS_CASES)), ids=[c[0] for c in REAL_LENS_CASES])
def test_real_lens_keyword(args, index):
    """ctest robustness_malformed_real_lens."""
    refused(args, "real_lens", index, *REAL_LENS_CASES[index])
