// SPDX-License-Identifier: AGPL-3.0-or-later
// The distortion profile: real chief rays against the paraxial image (see the header).

#include "plenoptic/truth/distortion_profile.h"

#include <algorithm>
#include <cmath>

#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"
#include "plenoptic/camera/rays.h"

namespace plenoptic {

namespace {

const int kSecantSteps = 40;

// First-order data in the optics frame: focal length and the z of the two focal points.
struct Conjugates {
    double f, front_focal_z, rear_focal_z;
};

// Where a traced prescription's chief rays are aimed: the plane of the paraxial entrance pupil,
// and, for the secant, the group in front of the stop (no clear apertures) and the stop's z.
class StopAim {
public:
    explicit StopAim(const PlenopticCamera& m) : m_(m), stop_index_(-1), stop_lens_z_(0)
    {
        if (!m.lens || !m.lens->traced())
            return;
        const std::vector<double> z = vertex_positions(m.prescription());
        for (std::size_t i = 0; i < m.prescription().surfaces.size(); ++i) {
            if (!m.prescription().surfaces[i].stop)
                continue;
            stop_index_ = int(i);
            stop_lens_z_ = z[i];
        }
        for (int i = 0; i < stop_index_; ++i) {
            LensSurface surface = m.prescription().surfaces[std::size_t(i)];
            surface.aperture_mm = INFINITY;
            front_.surfaces.push_back(surface);
        }
    }

    // Height (along y) at which the ray crosses the stop's plane; NaN when it cannot.
    double stop_height(Vec3 origin, Vec3 direction) const
    {
        const double length = m_.lens_length_mm();
        LensRay ray{Vec3{origin.x, origin.y, length - origin.z}, normalized(Vec3{direction.x, direction.y, -direction.z})};
        if (!front_.surfaces.empty()) {
            const Traced out = trace_from_object(front_, ray);
            if (out.result != TraceResult::Passed)
                return NAN;
            ray = out.ray;
        }
        if (!(ray.dir.z > 0))
            return NAN;
        const double t = (stop_lens_z_ - ray.origin.z) / ray.dir.z;
        return ray.origin.y + t * ray.dir.y;
    }

    bool traced() const { return stop_index_ >= 0; }

private:
    const PlenopticCamera& m_;
    int stop_index_;
    double stop_lens_z_;
    Prescription front_;
};

// The chief ray for an aim point (0, t, pupil_z): from the object point (finite) or along the
// given direction (object at infinity, the origin well in front of the lens).
struct ChiefRay {
    Vec3 origin, direction;
};

ChiefRay ray_for(bool at_infinity, Vec3 object_or_direction, double pupil_z, double start_z, double t)
{
    const Vec3 aim{0, t, pupil_z};
    if (!at_infinity)
        return ChiefRay{object_or_direction, aim - object_or_direction};
    const Vec3 d = object_or_direction;
    const double back = (start_z - pupil_z) / -d.z;  // d.z < 0: travels towards -z
    return ChiefRay{aim - back * d, d};
}

} // namespace

DistortionProfile distortion_profile(const PlenopticCamera& m, int count, const PlenopticCamera* through)
{
    // The object points are the camera's own; their chief rays are traced through `through`.
    const PlenopticCamera& t_camera = through ? *through : m;
    const int W = m.sensor.film.width, H = m.sensor.film.height;
    DistortionProfile out = DistortionProfile();
    out.valid = false;
    if (!m.lens || !m.lens->forms_image() || count < 2 || W <= 0 || H <= 0)
        return out;
    // An ideal thin lens has no paraxial data of its own: its focal points are at +-F.
    const bool thin = !m.lens->paraxial();
    if (!thin && !m.paraxial().valid)
        return out;

    Conjugates c;
    double pupil_z, start_z;  // the plane aimed at; a plane in front of the lens
    if (thin) {
        c = Conjugates{m.focal_length_mm(), m.focal_length_mm(), -m.focal_length_mm()};
        pupil_z = 0;
        start_z = 1;
    } else {
        const double L = m.lens_length_mm();
        c = Conjugates{m.paraxial().efl_mm, L - m.paraxial().front_focal_z, L - m.paraxial().rear_focal_z};
        pupil_z = L - m.paraxial().entrance_pupil_z;
        start_z = std::max(L, pupil_z) + 1;
    }
    out.image_plane_z_mm = -m.distance_mm;
    // Newton: x x' = f^2, x' from the rear focal point to the image, x from the front focal point to
    // the object, both positive away from the lens; magnification -x'/f.
    const double x_image = c.rear_focal_z - out.image_plane_z_mm;
    if (!(c.f > 0) || !(x_image >= 0) || !std::isfinite(x_image))
        return out;
    out.object_at_infinity = x_image <= 1e-12 * c.f;
    out.object_plane_z_mm = out.object_at_infinity ? INFINITY : c.front_focal_z + c.f * c.f / x_image;
    if (!out.object_at_infinity && !(out.object_plane_z_mm > start_z))
        return out;
    const double magnification = out.object_at_infinity ? 0 : x_image / c.f;  // |m|

    double largest = 0;
    const double corners[4][2] = {{0, 0}, {double(W), 0}, {0, double(H)}, {double(W), double(H)}};
    for (const auto& corner : corners) {
        const Vec3 s = m.sensor.point(corner[0], corner[1]);
        largest = std::max(largest, std::hypot(s.x, s.y));
    }

    const StopAim stop(t_camera);
    for (int i = 0; i < count; ++i) {
        const double relative = double(i) / (count - 1);
        const double h = relative * largest;
        // The object above the axis (+y); its paraxial image below it (-y).
        Vec3 object;
        if (out.object_at_infinity) {
            const double theta = std::atan(h / c.f);
            object = Vec3{0, -std::sin(theta), -std::cos(theta)};
        } else {
            object = Vec3{0, h / magnification, out.object_plane_z_mm};
        }
        double t = 0;
        if (stop.traced()) {
            // Secant on the aim point's height until the ray crosses the stop on the axis.
            double t0 = 0, t1 = 1e-3 * std::max(1.0, std::fabs(pupil_z));
            ChiefRay r0 = ray_for(out.object_at_infinity, object, pupil_z, start_z, t0);
            double y0 = stop.stop_height(r0.origin, r0.direction);
            for (int k = 0; k < kSecantSteps && std::isfinite(y0) && std::fabs(y0) > 1e-13; ++k) {
                const ChiefRay r1 = ray_for(out.object_at_infinity, object, pupil_z, start_z, t1);
                const double y1 = stop.stop_height(r1.origin, r1.direction);
                if (!std::isfinite(y1) || y1 == y0)
                    break;
                const double next = t1 - y1 * (t1 - t0) / (y1 - y0);
                t0 = t1;
                y0 = y1;
                t1 = next;
            }
            if (!std::isfinite(y0) || std::fabs(y0) > 1e-9)
                break;  // no chief ray through the stop's centre: the field ends here
            t = t0;
        }
        const ChiefRay chief = ray_for(out.object_at_infinity, object, pupil_z, start_z, t);
        const ImageRay image = t_camera.lens->to_image(chief.origin, chief.direction, false);
        if (!image.passed || !(image.dir.z < 0))
            break;
        const double along = (out.image_plane_z_mm - image.origin.z) / image.dir.z;
        const double real_y = image.origin.y + along * image.dir.y;
        const Vec3 d = normalized(chief.direction);
        DistortionSample sample;
        sample.relative_field = relative;
        sample.field_angle_deg = std::atan2(std::hypot(d.x, d.y), std::fabs(d.z)) * 180 / kPi;
        sample.paraxial_height_mm = h;
        sample.real_height_mm = -real_y;
        if (!std::isfinite(sample.real_height_mm) || !std::isfinite(sample.field_angle_deg))
            break;
        out.samples.push_back(sample);
    }
    out.valid = out.samples.size() >= 2;
    return out;
}

} // namespace plenoptic
