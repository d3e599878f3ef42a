// SPDX-License-Identifier: AGPL-3.0-or-later
// The pure optics of the plenoptic camera, one header per concern; this one includes them all.
//   plenoptic_rays.h               sensor points, lens lookup, generate_ray, chief rays, overlap lenses
//   plenoptic_projection.h         forward projection of 3-D points
//   plenoptic_microimage_lattice.h microimage centres, their lattice and its LFToolbox fit

#ifndef PLENOPTIC_OPTICS_H
#define PLENOPTIC_OPTICS_H

#include "plenoptic_microimage_lattice.h"
#include "plenoptic_projection.h"
#include "plenoptic_rays.h"

#endif
