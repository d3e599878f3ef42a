// SPDX-License-Identifier: AGPL-3.0-or-later
// The renderer's side of the plenoptic camera: one pixel, shaded by the pure optics in
// source/plenoptic/ with POV-Ray's tracer behind each ray; the render's outputs that follow the
// pixels (the depth map) see the scene through the same tracer first.

#include <cmath>
#include <limits>

#include "backend/frame.h"
#include "backend/math/vector.h"
#include "backend/render/tracepixel.h"
#include "backend/scene/camera.h"
#include "backend/support/task.h"
#include "plenoptic/camera/pixel.h"
#include "povray_glue/plenoptic_setup.h"
#include "povray_glue/plenoptic_render.h"

#include "base/povdebug.h"

namespace pov
{

namespace
{

void To_Scene(const plenoptic::Render& render, const plenoptic::OpticsRay& in, Ray& out)
{
	const plenoptic::CameraFrame& frame = render.frame();
	const double units_per_mm = 1.0 / render.model().mm_per_unit;
	// In the optics frame's world axes: location + (o.x right + o.y up + o.z direction) / mm_per_unit.
	const plenoptic::Vec3 along = in.origin_mm.x * frame.right + in.origin_mm.y * frame.up + in.origin_mm.z * frame.direction;
	const plenoptic::Vec3 origin = frame.location + units_per_mm * along;
	const plenoptic::Vec3 direction = in.dir.x * frame.right + in.dir.y * frame.up + in.dir.z * frame.direction;
	Make_Vector(out.Origin, origin.x, origin.y, origin.z);
	Make_Vector(out.Direction, direction.x, direction.y, direction.z);
	if (!render.frame_orthonormal())
		VNormalizeEq(out.Direction);
}

// The scene as the outputs see it from this thread: the first surface along a camera ray.
template <class FirstHit>
class Probe : public plenoptic::SceneProbe
{
	public:
		explicit Probe(FirstHit& first_hit) : first_hit_(first_hit) {}
		double first_hit(const plenoptic::OpticsRay& ray) { return first_hit_(ray); }
		void cooperate() { Task::CurrentTaskCooperate(); }
	private:
		FirstHit& first_hit_;
};

}

void TracePixel::TracePlenopticPixel(Colour& colour, DBL x, DBL y, DBL width, DBL height)
{
	// Made once by View::StartRender (Plenoptic_Start_Render) and carried in the copied camera.
	if (!camera.PlenopticRender)
		throw POV_EXCEPTION_STRING("plenoptic camera: the render has no plenoptic state (internal error).");
	plenoptic::Render& render = *camera.PlenopticRender;
	const plenoptic::PlenopticCamera& model = render.model();
	const int W = (int)width, H = (int)height;
	if (W != model.sensor.film.width || H != model.sensor.film.height)
		throw POV_EXCEPTION_STRING("plenoptic camera: a pixel of an image of another size than the render's (internal error).");
	// Antialiasing may ask for sub-pixel positions: the camera samples the whole pixel itself.
	const int i = (int)std::floor(x + 0.5), j = (int)std::floor(y + 0.5);

	if (render.traces_pixels() && !pretrace)
	{
		// Distance along an optics ray to the first surface; +inf where it hits nothing.
		auto first_hit = [&](const plenoptic::OpticsRay& optics_ray) -> double
		{
			Ray ray;
			ray.SetFlags(Ray::PrimaryRay, false, false, false, false, pretrace);
			To_Scene(render, optics_ray, ray);
			Intersection isect;
			return FindIntersection(isect, ray) ? isect.Depth : std::numeric_limits<double>::infinity();
		};
		Probe<decltype(first_hit)> scene(first_hit);
		render.pixel_traced(i, j, scene);
	}

	POV_ULONG traced = 0;  // camera rays into the scene, for the render statistics' "Samples"
	auto trace = [&](const plenoptic::OpticsRay& optics_ray) -> plenoptic::Rgbt
	{
		traced++;
		Ray ray;
		ray.SetFlags(Ray::PrimaryRay, false, false, false, false, pretrace);
		To_Scene(render, optics_ray, ray);
		// As the perspective camera: the containing interiors are those at the main lens.
		InitRayContainerState(ray);
		Colour col;
		Trace::TraceTicket ticket(maxTraceLevel, adcBailout, sceneData->outputAlpha);
		TraceRay(ray, col, 1.0, ticket, false, camera.Max_Ray_Distance);
		return plenoptic::Rgbt{col[pRED], col[pGREEN], col[pBLUE], col[pTRANSM]};
	};
	plenoptic::Rgbt value;
	if (render.keeps_white() && !pretrace)
	{
		// The white image's value of this pixel from the same samples (no second trace of the camera).
		double white = 0;
		value = plenoptic::shade_pixel_and_white(model, i, j, trace, &white);
		render.pixel_white(i, j, white);
	}
	else
		value = plenoptic::shade_pixel(model, i, j, trace);
	threadData->Stats()[Number_Of_Samples] += traced;
	colour = Colour(value.r, value.g, value.b, 0.0, value.t);
}


}
