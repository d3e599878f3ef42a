// SPDX-License-Identifier: AGPL-3.0-or-later
// The pure optics of the plenoptic camera, one header per concern; this one includes them all.
//   camera/rays.h               sensor points, lens lookup, generate_ray, chief rays, overlap lenses
//   projection/projection.h         forward projection of 3-D points
//   projection/microimage_lattice.h microimage centres, their lattice and its LFToolbox fit

#ifndef PLENOPTIC_OPTICS_H
#define PLENOPTIC_OPTICS_H

#include "plenoptic/projection/microimage_lattice.h"
#include "plenoptic/projection/projection.h"
#include "plenoptic/camera/rays.h"

#endif
