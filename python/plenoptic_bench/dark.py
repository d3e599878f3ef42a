# SPDX-License-Identifier: AGPL-3.0-or-later
"""Section dark: what the pixels no light reaches save on a Lytro-class camera."""
import statistics

from .util import LOCATION, log


# kVignettingProbesPerSample in source/plenoptic/camera/pixel.h.
VIGNETTING_PROBES_PER_SAMPLE = 4


def section_dark(b, size, results):
    import numpy as np
    log("dark pixels: Lytro-class camera at %dx%d" % (size, size))
    # Lytro Illum class: 1.4 um pixels, ~20 um hexagonal pitch, f/2 matched microlenses.
    lytro = ("plenoptic %s main_lens { thin_lens focal_length 30 f_number 2 focus_distance 2.5 } "
             "microlens_array { hexagonal pitch 0.02 focal_length 0.04 distance 0.04 } sensor { pixel_size 0.0014 } samples 4"
             % LOCATION)
    D = 30.0 * 2500 / (2500 - 30)
    # The same pixels and samples with every sample traced: a pinhole camera over the same sensor.
    variants = {
        "Lytro-class plenoptic, 4 samples": b.scene("dark_lytro", lytro),
        "every sample traced (pinhole main lens, no array), 4 samples": b.scene("dark_all",
            "plenoptic %s main_lens { pinhole distance %.12g } sensor { pixel_size 0.0014 } samples 4" % (LOCATION, D)),
    }
    res = b.compare(variants, size, size)
    times = {k: v[2] for k, v in res.items()}
    # In a render of a world that is white everywhere (16 samples), a pixel no light reaches is
    # black, and a pixel's value is the fraction of its sample points that pass the apertures:
    # of its 16 samples, or of the 4 x 16 points a partly vignetted pixel looks at (the camera's
    # vignetting probes; the file is linear). So the mean of a channel over the pixels is the
    # fraction of samples traced into the scene. (That holds while no pixel sums light through
    # several lenses, which could exceed 1: checked below by the values being multiples of 1/64.)
    samples = 16
    points = samples * VIGNETTING_PROBES_PER_SAMPLE
    img = b.white("dark_white", lytro.replace("samples 4", "samples %d" % samples), size, size)
    dark = float(np.mean(img.max(axis=2) == 0))
    lit_samples = float(np.mean(img[..., 0]))
    off_grid = float(np.mean(np.abs(img[..., 0] * points - np.round(img[..., 0] * points)) > 1e-3))
    if off_grid > 0:
        log("dark: %.2f%% of the pixels are not a multiple of 1/%d: the lit-sample fraction is approximate"
            % (100 * off_grid, points))
    rows = [{"camera": k, "median_s": statistics.median(v), "runs_s": v} for k, v in times.items()]
    t = statistics.median(times["Lytro-class plenoptic, 4 samples"])
    # Each traced sample costs about the same: t = lit * N * c, so the blocked (1 - lit) * N
    # samples would have cost t (1 / lit - 1) more.
    saving = t * (1 / lit_samples - 1) if lit_samples > 0 else None
    results["dark"] = {"size": size, "dark_pixel_fraction": dark, "white_samples": samples,
                       "lit_sample_fraction": lit_samples, "pixels_off_sample_grid": off_grid,
                       "estimated_untraced_s": saving, "rows": rows}
