# SPDX-License-Identifier: AGPL-3.0-or-later
"""One POV-Ray run of a data set: an item, or one row band of it, into a folder of its own."""

import os
import socket

from ..povray import povray_command as _povray_command, run_povray


def image_extension(spec):
    """The main image's extension: .exr when the spec's options choose OpenEXR (+FE), else .png
    (the default: 16-bit linear PNG)."""
    extension = ".png"
    for option in spec.povray_options:
        if option[:3].upper() == "+FE":
            extension = ".exr"
        elif option[:2].upper() == "+F":
            extension = ".png"
    return extension


DECLARATIONS = "declarations.inc"


def povray_command(povray, spec, item, out_path, band=None):
    """The command that renders `item` (or rows band = (first, last), 0-based, of it) to
    out_path. Defaults first (16-bit linear PNG, no display, no pause), then the spec's options,
    then the item's values: DECLARATIONS beside out_path, read before the scene (Include_Header)."""
    cmd = _povray_command(povray, spec.scene, out_path, spec.width, spec.height,
                          ["-D", "-P", "+L" + os.path.dirname(spec.scene), "+FN16", "File_Gamma=1.0"])
    cmd += spec.povray_options
    cmd += ["Include_Header=" + os.path.join(os.path.dirname(out_path), DECLARATIONS)]
    if band is not None:
        cmd += ["+SR%d" % (band[0] + 1), "+ER%d" % (band[1] + 1)]
    return cmd


class RenderResult:
    def __init__(self, ok, command, seconds, cpu_seconds, log, status):
        self.ok = ok
        self.command = command
        self.seconds = seconds
        self.cpu_seconds = cpu_seconds
        self.log = log
        self.status = status

    def record(self):
        return {"render_seconds": round(self.seconds, 3), "cpu_seconds": round(self.cpu_seconds, 3),
                "host": socket.gethostname(), "command": self.command}


def render(povray, spec, item, folder, band=None):
    """Renders into `folder` (the image is <folder>/<item id><ext>, its sidecars beside it).
    KeyboardInterrupt stops POV-Ray at once (it is sent SIGINT and waited for) and propagates."""
    out = os.path.join(folder, item.id + image_extension(spec))
    with open(os.path.join(folder, DECLARATIONS), "w") as f:
        f.write("// plenoptic-dataset: item %s's values\n" % item.id + item.declarations())
    cmd = povray_command(povray, spec, item, out, band)
    log_path = os.path.join(folder, "render.log")
    with open(log_path, "w") as log:
        log.write("$ %s\n" % " ".join(cmd))
    # Ctrl-C: POV-Ray (in its own session) is sent SIGINT and waited for, then this goes on.
    run = run_povray(cmd, cwd=folder, log=log_path)
    seconds, cpu, text, status = run.seconds, run.cpu_seconds, run.output, run.returncode
    ok = status == 0 and os.path.exists(out)
    if status == 0 and not ok:
        text += "\nplenoptic-dataset: POV-Ray exited 0 but wrote no %s\n" % os.path.basename(out)
    return RenderResult(ok, cmd, seconds, cpu, text, status)
