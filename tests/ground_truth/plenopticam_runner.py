# SPDX-License-Identifier: AGPL-3.0-or-later
"""Runs PlenoptiCam (the Python package plenopticam) on one of our renders, inside the virtual
environment test_plenopticam.py makes for it: calibration from the white image, then alignment
and view extraction of the raw, as PlenoptiCam's own command line does them.

    python plenopticam_runner.py RAW.npy WHITE.npy OUTDIR

RAW.npy and WHITE.npy are the linear images (H x W x 3, float64) as test_plenopticam.py read them
with OpenImageIO (the venv has no OpenImageIO). Writes OUTDIR/centroids.npy (PlenoptiCam's
microimage centres: rows of y, x, row index, column index) and OUTDIR/central_view.npy, and
prints one JSON line with the pattern, the pitch and the view array's shape."""
import json
import os
import sys

import numpy as np
from plenopticam import lfp_aligner, lfp_calibrator, lfp_extractor
from plenopticam.cfg import PlenopticamConfig
from plenopticam.misc import PlenopticamStatus


def main(raw_path, white_path, out):
    os.makedirs(out, exist_ok=True)
    cfg = PlenopticamConfig()
    cfg.default_values()
    cfg.params[cfg.opt_prnt] = False
    # PlenoptiCam writes its calibration and views beside these (never read back here).
    cfg.params[cfg.lfp_path] = os.path.join(out, "raw.png")
    cfg.params[cfg.cal_path] = os.path.join(out, "white.png")
    # Views only: no refocusing, depth or colour automation; devignetting with the white image on.
    for key in (cfg.opt_refo, cfg.opt_dpth, cfg.opt_cont, cfg.opt_colo, cfg.opt_awb_, cfg.opt_sat_):
        cfg.params[key] = False
    cfg.params[cfg.opt_vign] = True
    status = PlenopticamStatus()
    white = np.load(white_path)
    raw = np.load(raw_path)
    lfp_calibrator.LfpCalibrator(white, cfg, status).main()
    centroids = np.asarray(cfg.calibs[cfg.mic_list], dtype=np.float64)
    np.save(os.path.join(out, "centroids.npy"), centroids)
    report = {"centroids": int(len(centroids)), "pattern": cfg.calibs[cfg.pat_type]}
    if len(centroids):
        cfg.load_cal_data()
        aligner = lfp_aligner.LfpAligner(raw, cfg, status, white)
        aligner.main()
        # PlenoptiCam 0.9.3's cropper cuts (pitch - patch) // 2 from each side of an aligned
        # microimage and fails when pitch - patch is odd (an even aligned pitch with its default
        # patch of 7): then its patch size option is set to 8, as a user would. When the aligned
        # pitches of the two axes differ in parity neither works: the report says so.
        views = None
        for patch in (7, 8):
            try:
                cfg.params[cfg.ptc_leng] = patch
                extractor = lfp_extractor.LfpExtractor(aligner.lfp_img, cfg=cfg, sta=status)
                extractor.main()
                views = extractor.vp_img_linear
                report["patch"] = patch
                break
            except ValueError as error:
                report["decode_error_patch_%d" % patch] = str(error)
        if views is not None:
            centre = views.shape[0] // 2
            np.save(os.path.join(out, "central_view.npy"), np.asarray(views[centre, centre], dtype=np.float64))
            report["views"] = list(views.shape)
    print(json.dumps(report))
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
