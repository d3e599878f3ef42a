// SPDX-License-Identifier: AGPL-3.0-or-later
// The renderer's side of the plenoptic camera: one pixel, shaded by the pure optics in
// source/plenoptic/ with POV-Ray's tracer behind each ray.

#include <cmath>
#include <limits>

#include "backend/frame.h"
#include "backend/math/vector.h"
#include "backend/render/tracepixel.h"
#include "backend/scene/camera.h"
#include "plenoptic/plenoptic_pixel.h"
#include "povray_glue/plenoptic_setup.h"
#include "povray_glue/plenoptic_sidecar.h"

#include "base/povdebug.h"

namespace pov
{

namespace
{

// The optics frame in the scene: +x right, +y up, +z towards the scene, all unit length.
plenoptic::CameraFrame Frame_Of(const Camera& camera)
{
	plenoptic::CameraFrame frame;
	Vector3d right(camera.Right), up(camera.Up), direction(camera.Direction);
	right.normalize();
	up.normalize();
	direction.normalize();
	for (int i = 0; i < 3; i++)
	{
		frame.location[i] = camera.Location[i];
		frame.right[i] = right[i];
		frame.up[i] = up[i];
		frame.direction[i] = direction[i];
	}
	return frame;
}

void To_Scene(const plenoptic::RenderState& state, double mm_per_unit, const plenoptic::OpticsRay& in, Ray& out)
{
	const plenoptic::CameraFrame& frame = state.frame;
	const double units_per_mm = 1.0 / mm_per_unit;
	for (int i = 0; i < 3; i++)
	{
		out.Origin[i] = frame.location[i] + (in.origin_mm[0] * frame.right[i] + in.origin_mm[1] * frame.up[i] +
		                                     in.origin_mm[2] * frame.direction[i]) * units_per_mm;
		out.Direction[i] = in.dir[0] * frame.right[i] + in.dir[1] * frame.up[i] + in.dir[2] * frame.direction[i];
	}
	if (!state.frame_orthonormal)
		VNormalizeEq(out.Direction);
}

}

void TracePixel::TracePlenopticPixel(Colour& colour, DBL x, DBL y, DBL width, DBL height)
{
	const plenoptic::CameraSetup& setup = *camera.Plenoptic;
	const plenoptic::Model& model = setup.model;
	const int W = (int)width, H = (int)height;
	// Antialiasing may ask for sub-pixel positions: the camera samples the whole pixel itself.
	const int i = (int)std::floor(x + 0.5), j = (int)std::floor(y + 0.5);
	const plenoptic::RenderState *state = plenoptic::sidecar_current(camera.Plenoptic.get(), W, H);
	if (state == NULL)
		state = plenoptic::sidecar_register(camera.Plenoptic, Frame_Of(camera), W, H);
	float *depth = state->depth;

	if (depth != NULL)
	{
		// Distance along a pixel's chief ray, from the lens it leaves to the first surface;
		// +inf where it hits nothing, -1 where no sample of the pixel passes the apertures.
		auto depth_of = [&](int column, int row) -> float
		{
			if (!plenoptic::pixel_receives_light(model, column, row, W, H))
				return -1.0f;
			Ray ray;
			ray.SetFlags(Ray::PrimaryRay, false, false, false, false, pretrace);
			To_Scene(*state, model.mm_per_unit, plenoptic::chief_ray(model, W, H, column, row), ray);
			Intersection isect;
			return FindIntersection(isect, ray) ? (float)isect.Depth : std::numeric_limits<float>::infinity();
		};
		// Every thread helps fill the whole depth map before shading its first pixel.
		for (int row = plenoptic::sidecar_claim_depth_row(); row >= 0; row = plenoptic::sidecar_claim_depth_row())
			for (int column = 0; column < W; column++)
				depth[size_t(row) * W + column] = depth_of(column, row);
	}

	POV_ULONG traced = 0;  // camera rays into the scene, for the render statistics' "Samples"
	plenoptic::Rgbt value = plenoptic::shade_pixel(model, i, j, W, H,
		[&](const plenoptic::OpticsRay& optics_ray) -> plenoptic::Rgbt
		{
			traced++;
			Ray ray;
			ray.SetFlags(Ray::PrimaryRay, false, false, false, false, pretrace);
			To_Scene(*state, model.mm_per_unit, optics_ray, ray);
			// As the perspective camera: the containing interiors are those at the main lens.
			InitRayContainerState(ray);
			Colour col;
			Trace::TraceTicket ticket(maxTraceLevel, adcBailout, sceneData->outputAlpha);
			TraceRay(ray, col, 1.0, ticket, false, camera.Max_Ray_Distance);
			return plenoptic::Rgbt{col[pRED], col[pGREEN], col[pBLUE], col[pTRANSM]};
		});
	threadData->Stats()[Number_Of_Samples] += traced;
	colour = Colour(value.r, value.g, value.b, 0.0, value.t);
}


}
