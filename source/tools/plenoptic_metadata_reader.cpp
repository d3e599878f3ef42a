// SPDX-License-Identifier: AGPL-3.0-or-later
// Metadata JSON (parsed by nlohmann-json) -> CameraParams -> PlenopticCamera, with a message naming the
// field for every refusal.

#include "plenoptic_metadata_reader.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace plenoptic {

namespace {

using Json = nlohmann::json;

// Thrown inside this file only; parse_metadata turns it into `error`.
struct FieldError : std::runtime_error {
    explicit FieldError(const std::string& message) : std::runtime_error(message) {}
};

// Printable ASCII as is; any other byte as \xNN, so that a message is one line of valid text
// whatever the file held.
std::string printable(const std::string& text)
{
    std::string out;
    for (unsigned char c : text) {
        if (c >= 0x20 && c < 0x7f) {
            out += char(c);
        } else {
            char buffer[8];
            std::snprintf(buffer, sizeof buffer, "\\x%02x", c);
            out += buffer;
        }
    }
    return out;
}

const char* type_name(const Json& v)
{
    switch (v.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::boolean: return "a boolean";
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float: return "a number";
    case Json::value_t::string: return "a string";
    case Json::value_t::array: return "an array";
    case Json::value_t::object: return "an object";
    default: return "a value of another kind";
    }
}

std::string describe(const Json& v)
{
    if (v.is_number())
        return "the number " + format_number(v.get<double>());
    if (v.is_string())
        return "the string " + printable(v.dump());  // quoted and escaped
    return type_name(v);
}

[[noreturn]] void refuse(const std::string& path, const std::string& must, const Json& found)
{
    throw FieldError("field '" + path + "' must be " + must + ", found " + describe(found));
}

std::string join(const std::string& parent, const std::string& key)
{
    return parent.empty() ? key : parent + "." + key;
}

const Json& member(const Json& object, const std::string& parent, const std::string& key)
{
    const auto it = object.find(key);
    if (it == object.end())
        throw FieldError("field '" + join(parent, key) + "' is missing");
    return *it;
}

const Json& object_member(const Json& object, const std::string& parent, const std::string& key)
{
    const Json& v = member(object, parent, key);
    if (!v.is_object())
        refuse(join(parent, key), "an object", v);
    return v;
}

double finite_number(const Json& v, const std::string& path)
{
    if (!v.is_number() || !std::isfinite(v.get<double>()))
        refuse(path, "a finite number", v);
    return v.get<double>();
}

double positive_number(const Json& v, const std::string& path)
{
    if (!v.is_number() || !std::isfinite(v.get<double>()) || !(v.get<double>() > 0))
        refuse(path, "a positive number", v);
    return v.get<double>();
}

std::string string_member(const Json& object, const std::string& parent, const std::string& key)
{
    const Json& v = member(object, parent, key);
    if (!v.is_string())
        refuse(join(parent, key), "a string", v);
    return v.get<std::string>();
}

// A fixed-length array of finite numbers (positive ones when `positive`).
void numbers(const Json& object, const std::string& parent, const std::string& key, int count, bool positive,
             double* out)
{
    const std::string path = join(parent, key);
    const Json& v = member(object, parent, key);
    const std::string must = "an array of " + std::to_string(count) + (positive ? " positive numbers" : " finite numbers");
    if (!v.is_array() || v.size() != size_t(count))
        refuse(path, must, v);
    for (int i = 0; i < count; ++i) {
        const Json& item = v[size_t(i)];
        if (!item.is_number() || !std::isfinite(item.get<double>()) || (positive && !(item.get<double>() > 0)))
            refuse(path + "[" + std::to_string(i) + "]", positive ? "a positive number" : "a finite number", item);
        out[i] = item.get<double>();
    }
}

// A whole number written without fraction or exponent ("640", not "640.0" or "6.4e2").
int positive_integer(const Json& object, const std::string& parent, const std::string& key)
{
    const Json& v = member(object, parent, key);
    if (!v.is_number_integer() || !(v.get<double>() >= 1) || !(v.get<double>() <= 1e9))
        refuse(join(parent, key), "a positive whole number", v);
    return int(v.get<double>());
}

void check_close(const std::string& path, double stored, double derived, double scale, const std::string& from)
{
    if (!(std::fabs(stored - derived) <= 1e-6 * scale))
        throw FieldError("field '" + path + "' is " + format_number(stored) + " but " + from + " give " +
                         format_number(derived) + ": the metadata file is inconsistent (edited?)");
}

// Duplicate keys: RFC 8259 leaves their meaning open (Python's json takes the last, others the
// first), so a file with one is refused rather than read one way or the other. The parser's
// callback sees every key; one set of keys per open object.
class DuplicateKeyCheck {
public:
    bool operator()(int /*depth*/, Json::parse_event_t event, Json& parsed)
    {
        switch (event) {
        case Json::parse_event_t::object_start:
        case Json::parse_event_t::array_start:
            open(event == Json::parse_event_t::object_start);
            break;
        case Json::parse_event_t::object_end:
        case Json::parse_event_t::array_end:
            if (!frames_.empty())
                frames_.pop_back();
            break;
        case Json::parse_event_t::key: {
            Frame& frame = frames_.back();
            const std::string key = parsed.get<std::string>();
            if (!frame.keys.insert(key).second) {
                const std::string where = path();
                throw FieldError("duplicate key '" + printable(key) + "' in " +
                                 (where.empty() ? std::string("the top-level object") : "the object '" + where + "'") +
                                 ": a key may appear only once in an object");
            }
            frame.last_key = key;
            break;
        }
        default:
            break;
        }
        return true;  // keep everything
    }

private:
    struct Frame {
        bool object;
        bool in_array = false; // an element of an array (else `name` is its key in the parent)
        std::string name;
        std::string last_key;  // objects: the key being read
        std::set<std::string> keys;
    };

    void open(bool object)
    {
        Frame frame;
        frame.object = object;
        if (!frames_.empty()) {
            frame.in_array = !frames_.back().object;
            frame.name = frames_.back().last_key;
        }
        frames_.push_back(std::move(frame));
    }

    // "microlens_array", "a.b[]", ... of the innermost open object (built only for a message).
    std::string path() const
    {
        std::string out;
        for (size_t i = 1; i < frames_.size(); ++i) {
            if (frames_[i].in_array) {
                out += "[]";
                continue;
            }
            if (!out.empty())
                out += '.';
            out += printable(frames_[i].name);
        }
        return out;
    }

    std::vector<Frame> frames_;
};

// nlohmann's message without its "[json.exception.parse_error.101] parse error at " prefix:
// "line 3, column 7: syntax error while parsing value - invalid string: ...".
std::string parse_message(const std::string& what)
{
    std::string message = what;
    if (message.compare(0, 1, "[") == 0) {
        const size_t close = message.find("] ");
        if (close != std::string::npos)
            message.erase(0, close + 2);
    }
    const std::string prefix = "parse error at ";
    if (message.compare(0, prefix.size(), prefix) == 0)
        message.erase(0, prefix.size());
    return printable(message);
}

// The surfaces as the render used them (stop at its working diameter): no aperture or f_number
// is applied on top of them.
void read_prescription(const Json& v, const std::string& parent, MainLensParams* m)
{
    const Json& surfaces = member(v, parent, "surfaces");
    if (!surfaces.is_array())
        refuse(parent + ".surfaces", "an array of surfaces", surfaces);
    m->prescription = Prescription();
    for (size_t i = 0; i < surfaces.size(); ++i) {
        const std::string row = parent + ".surfaces[" + std::to_string(i) + "]";
        const Json& s = surfaces[i];
        if (!s.is_object())
            refuse(row, "an object", s);
        const Json& stop = member(s, row, "stop");
        if (!stop.is_boolean())
            refuse(row + ".stop", "true or false", stop);
        LensSurface surface;
        surface.stop = stop.get<bool>();
        surface.radius_mm = finite_number(member(s, row, "radius_mm"), row + ".radius_mm");
        surface.thickness_mm = finite_number(member(s, row, "thickness_mm"), row + ".thickness_mm");
        surface.ior = finite_number(member(s, row, "ior"), row + ".ior");
        surface.aperture_mm = positive_number(member(s, row, "aperture_mm"), row + ".aperture_mm");
        surface.line = 0;
        // The medium's glass: absent when it does not disperse (the camera checks it with the lens).
        if (s.contains("abbe_number"))
            surface.glass.abbe = finite_number(s["abbe_number"], row + ".abbe_number");
        if (s.contains("sellmeier")) {
            const Json& sellmeier = s["sellmeier"];
            if (!sellmeier.is_object())
                refuse(row + ".sellmeier", "an object {\"b\": [B1, B2, B3], \"c_um2\": [C1, C2, C3]}", sellmeier);
            surface.glass.sellmeier = true;
            numbers(sellmeier, row + ".sellmeier", "b", 3, false, surface.glass.sellmeier_b);
            numbers(sellmeier, row + ".sellmeier", "c_um2", 3, false, surface.glass.sellmeier_c_um2);
        }
        // A conic or aspheric surface's terms (absent for a sphere or a plane).
        if (s.contains("conic"))
            surface.conic = finite_number(s["conic"], row + ".conic");
        if (s.contains("aspheric")) {
            const Json& terms = s["aspheric"];
            if (!terms.is_array() || terms.empty() || terms.size() > size_t(LensSurface::kMaxAspheric))
                refuse(row + ".aspheric", "an array of 1 to 8 numbers (a4, a6, ..., a18)", terms);
            surface.aspheric_count = int(terms.size());
            for (size_t j = 0; j < terms.size(); ++j)
                surface.aspheric[j] = finite_number(terms[j], row + ".aspheric[" + std::to_string(j) + "]");
        }
        m->prescription.surfaces.push_back(surface);
    }
    const Json& blades = member(v, parent, "blades");
    if (!blades.is_number_integer() || !(blades.get<double>() == 0 || (blades.get<double>() >= 3 && blades.get<double>() <= kMaxBlades)))
        refuse(parent + ".blades", "0 or a whole number from 3 to " + std::to_string(kMaxBlades), blades);
    m->blades = int(blades.get<double>());
    m->blade_rotation_deg = finite_number(member(v, parent, "blade_rotation_deg"), parent + ".blade_rotation_deg");
    const Json& file = member(v, parent, "lens_file");
    if (file.is_string())
        m->lens_file = file.get<std::string>();
    else if (!file.is_null())
        refuse(parent + ".lens_file", "a file name or null", file);
    m->has_prescription = true;
}

// Each main-lens kind's own members of main_lens (what its add_metadata writes), read back into
// the parameters that make the same lens. `main` is the section, `parent` its path.
void read_pinhole(const Json& main, const std::string& parent, MainLensParams& m)
{
    (void)main;
    (void)parent;
    m.type = MainLensType::Pinhole;
}

void read_thin_lens(const Json& main, const std::string& parent, MainLensParams& m)
{
    m.type = MainLensType::ThinLens;
    m.has_focal_length = true;
    m.focal_length_mm = positive_number(member(main, parent, "focal_length_mm"), parent + ".focal_length_mm");
    m.has_aperture = true;
    m.aperture_mm = positive_number(member(main, parent, "aperture_mm"), parent + ".aperture_mm");
    const Json& n = member(main, parent, "f_number");
    const double f_number = positive_number(n, parent + ".f_number");
    check_close(parent + ".f_number", f_number, m.focal_length_mm / m.aperture_mm, f_number,
                "focal_length_mm / aperture_mm");
    if (main.contains("distortion")) {
        const std::string d = parent + ".distortion";
        const Json& distortion = object_member(main, parent, "distortion");
        numbers(distortion, d, "radial", 3, false, m.distortion.radial);
        numbers(distortion, d, "tangential", 2, false, m.distortion.tangential);
        m.has_distortion = true;
        const double plane = finite_number(member(distortion, d, "plane_z_mm"), d + ".plane_z_mm");
        const double D = positive_number(member(main, parent, "distance_mm"), parent + ".distance_mm");
        check_close(d + ".plane_z_mm", plane, -D, D, "-main_lens.distance_mm");
    }
}

// thick_lens and prescription: the same members, the surfaces and their paraxial data.
void read_real_lens(const Json& main, const std::string& parent, MainLensParams& m)
{
    read_prescription(object_member(main, parent, "prescription"), parent + ".prescription", &m);
    const double f_number = positive_number(member(main, parent, "f_number"), parent + ".f_number");
    // The f-number of the aperture that limits the axial beam to the array (or sensor) at D.
    const double D = positive_number(member(main, parent, "distance_mm"), parent + ".distance_mm");
    check_close(parent + ".f_number", f_number, paraxial_data(effective_prescription(m), 0, D).f_number, f_number,
                "the surfaces of main_lens.prescription and main_lens.distance_mm");
}

void read_thick_lens(const Json& main, const std::string& parent, MainLensParams& m)
{
    m.type = MainLensType::ThickLens;
    read_real_lens(main, parent, m);
}

void read_traced_lens(const Json& main, const std::string& parent, MainLensParams& m)
{
    m.type = MainLensType::Prescription;
    read_real_lens(main, parent, m);
}

// The kinds by the name main_lens.type gives them (MainLens::kind_name).
struct MainLensReader {
    const char* type;
    void (*read)(const Json& main, const std::string& parent, MainLensParams& m);
};
const MainLensReader kMainLensReaders[] = {
    {"pinhole", read_pinhole},
    {"thin_lens", read_thin_lens},
    {"thick_lens", read_thick_lens},
    {"prescription", read_traced_lens},
};

void read_main_lens(const Json& root, CameraParams* params)
{
    const std::string parent = "main_lens";
    const Json& main = object_member(root, "", parent);
    const std::string type = string_member(main, parent, "type");
    MainLensParams& m = params->main;
    if (type == "none")
        return;  // no main lens: given stays false
    const MainLensReader* reader = nullptr;
    for (const MainLensReader& r : kMainLensReaders)
        if (type == r.type)
            reader = &r;
    if (reader == nullptr)
        refuse(parent + ".type", "\"thin_lens\", \"pinhole\", \"thick_lens\", \"prescription\" or \"none\"",
               member(main, parent, "type"));
    m.given = true;
    reader->read(main, parent, m);
    // D as resolved by the render, whether the scene gave focus_distance or distance.
    m.has_distance = true;
    m.distance_mm = positive_number(member(main, parent, "distance_mm"), parent + ".distance_mm");
}

void read_array(const Json& root, CameraParams* params, const std::string& folder)
{
    const std::string parent = "microlens_array";
    const Json& v = member(root, "", parent);
    if (v.is_null())
        return;
    if (!v.is_object())
        refuse(parent, "an object or null", v);
    ArrayParams& a = params->array;
    a.given = true;
    const std::string grid = string_member(v, parent, "grid");
    if (grid == "hexagonal")
        a.grid = GridType::Hexagonal;
    else if (grid == "rectangular")
        a.grid = GridType::Rectangular;
    else
        refuse(parent + ".grid", "\"hexagonal\" or \"rectangular\"", member(v, parent, "grid"));
    const std::string lens = string_member(v, parent, "lens");
    const Json& focal = member(v, parent, "focal_lengths_mm");
    if (!focal.is_array())
        refuse(parent + ".focal_lengths_mm", "an array", focal);
    a.has_lens = true;
    if (lens == "pinhole") {
        a.lens = MicrolensType::Pinhole;
        if (!focal.empty())
            refuse(parent + ".focal_lengths_mm", "empty for pinhole microlenses", focal);
        a.focal_length_count = 0;
    } else if (lens == "thin_lens") {
        a.lens = MicrolensType::ThinLens;
        const size_t count = focal.size();
        if (count != 1 && (count != 3 || a.grid != GridType::Hexagonal))
            refuse(parent + ".focal_lengths_mm",
                   a.grid == GridType::Hexagonal ? "an array of 1 or 3 positive numbers" : "an array of 1 positive number",
                   focal);
        a.focal_length_count = int(count);
        for (size_t i = 0; i < count; ++i)
            a.focal_lengths_mm[i] =
                positive_number(focal[i], parent + ".focal_lengths_mm[" + std::to_string(i) + "]");
    } else if (lens == "refracting") {
        // The shape as written; focal_lengths_mm (the paraxial focal length) follows from it.
        a.lens = MicrolensType::Refracting;
        a.focal_length_count = 0;
        const std::string where = parent + ".refracting";
        const Json& r = member(v, parent, "refracting");
        if (!r.is_object())
            refuse(where, "an object", r);
        const Json& surface = member(r, where, "surface");
        if (!surface.is_object())
            refuse(where + ".surface", "an object", surface);
        a.refracting.radius_mm = positive_number(member(surface, where + ".surface", "radius_mm"), where + ".surface.radius_mm");
        a.refracting.conic = finite_number(member(surface, where + ".surface", "conic"), where + ".surface.conic");
        a.refracting.ior = positive_number(member(r, where, "ior"), where + ".ior");
        a.refracting.cap_mm = positive_number(member(r, where, "thickness_mm"), where + ".thickness_mm");
        a.refracting.substrate_mm = positive_number(member(r, where, "substrate_mm"), where + ".substrate_mm");
        const std::string side = string_member(r, where, "curved_side");
        if (side != "scene" && side != "sensor")
            refuse(where + ".curved_side", "\"scene\" or \"sensor\"", member(r, where, "curved_side"));
        a.refracting.curved_towards_scene = side == "scene";
    } else {
        refuse(parent + ".lens", "\"thin_lens\", \"pinhole\" or \"refracting\"", member(v, parent, "lens"));
    }
    a.has_pitch = true;
    a.pitch_mm = positive_number(member(v, parent, "pitch_mm"), parent + ".pitch_mm");
    a.has_distance = true;
    a.distance_mm = positive_number(member(v, parent, "distance_mm"), parent + ".distance_mm");
    numbers(v, parent, "rotate_deg", 3, false, a.rotate_deg);
    numbers(v, parent, "translate_mm", 3, false, a.translate_mm);
    // The microlenses' Abbe number: absent when they do not disperse.
    if (v.contains("abbe_number"))
        a.abbe = finite_number(v["abbe_number"], parent + ".abbe_number");
    // A real array: fill factor, gap, baffles, and its manufacturing errors (drawn again from
    // their seed, or read from the microimages file beside the metadata, which lists each lens of
    // the picture as it was).
    if (v.contains("fill_factor")) {
        a.fill_factor = positive_number(v["fill_factor"], parent + ".fill_factor");
        a.mask = string_member(v, parent, "gap") == "masked";
        const Json& baffles = member(v, parent, "baffles");
        if (!baffles.is_boolean())
            refuse(parent + ".baffles", "true or false", baffles);
        a.baffles = baffles.get<bool>();
    }
    if (v.contains("errors")) {
        const std::string where = parent + ".errors";
        const Json& e = object_member(v, parent, "errors");
        const std::string source = string_member(e, where, "source");
        if (source == "drawn") {
            a.has_errors = true;
            a.errors.position_sd_mm = finite_number(member(e, where, "position_sd_mm"), where + ".position_sd_mm");
            a.errors.position_sd_z_mm = finite_number(member(e, where, "position_sd_z_mm"), where + ".position_sd_z_mm");
            a.errors.focal_sd = finite_number(member(e, where, "focal_length_sd"), where + ".focal_length_sd");
            a.errors.rotation_deg = finite_number(member(e, where, "rotation_deg"), where + ".rotation_deg");
            const Json& seed = member(e, where, "seed");
            if (!seed.is_number_integer())
                refuse(where + ".seed", "a whole number", seed);
            a.errors.seed = seed.get<std::int64_t>();
        } else if (source == "lens_table") {
            const Json& microimages = member(root, "", "microimages");
            if (!microimages.is_object() || folder.empty())
                refuse(where, "errors that a reader can rebuild: a lens table needs the microimages file beside the "
                              "metadata (read the metadata file, not its text)", e);
            const std::string file = folder + "/" + string_member(microimages, "microimages", "file");
            std::ifstream in(file.c_str(), std::ios::binary);
            std::ostringstream text;
            text << in.rdbuf();
            if (!in)
                refuse(where, "a lens table's lenses, read from the microimages file " + file + " (which cannot be opened)", e);
            const ParsedLensTable table = parse_lens_table(text.str(), a.pitch_mm);
            if (!table.error.empty())
                refuse(where, "a lens table's lenses from " + file + " (line " + std::to_string(table.error_line) + ": " +
                                  table.error + ")", e);
            a.lens_table_file = file;
            a.lens_table = std::make_shared<const std::vector<LensTableRow>>(table.rows);
        } else {
            refuse(where + ".source", "\"drawn\" or \"lens_table\"", member(e, where, "source"));
        }
    }
}

void read_frame(const Json& root, CameraFrame* frame)
{
    const std::string parent = "camera_frame";
    const Json& f = object_member(root, "", parent);
    double axes[4][3];
    numbers(f, parent, "location", 3, false, axes[0]);
    numbers(f, parent, "right", 3, false, axes[1]);
    numbers(f, parent, "up", 3, false, axes[2]);
    numbers(f, parent, "direction", 3, false, axes[3]);
    frame->location = Vec3{axes[0][0], axes[0][1], axes[0][2]};
    frame->right = Vec3{axes[1][0], axes[1][1], axes[1][2]};
    frame->up = Vec3{axes[2][0], axes[2][1], axes[2][2]};
    frame->direction = Vec3{axes[3][0], axes[3][1], axes[3][2]};
    const Vec3 r = frame->right, u = frame->up, d = frame->direction;
    const double volume = dot(r, cross(u, d));
    if (!(std::fabs(volume) > 1e-9 * length(r) * length(u) * length(d)) || !std::isfinite(volume))
        throw FieldError("field 'camera_frame': right, up and direction are linearly dependent "
                         "(they must span 3-D space)");
}

void read_all(const Json& root, RenderMetadata* out, const std::string& folder)
{
    if (!root.is_object())
        refuse("(top level)", "an object", root);
    const Json& format = member(root, "", "format");
    if (!format.is_string() || format.get<std::string>() != "povray-plenoptic-metadata")
        refuse("format", "\"povray-plenoptic-metadata\"", format);
    const Json& version = member(root, "", "version");
    if (!version.is_number() || version.get<double>() != 1)
        refuse("version", "1 (the only version this tool reads)", version);

    const Json& image = object_member(root, "", "image");
    out->width = positive_integer(image, "image", "width");
    out->height = positive_integer(image, "image", "height");

    CameraParams& p = out->params;
    p = CameraParams();
    p.mm_per_unit = positive_number(member(root, "", "mm_per_unit"), "mm_per_unit");
    read_frame(root, &out->frame);
    read_main_lens(root, &p);
    read_array(root, &p, folder);

    const Json& sensor = object_member(root, "", "sensor");
    numbers(sensor, "sensor", "pixel_size_mm", 2, true, p.sensor.pixel_size_mm);
    numbers(sensor, "sensor", "offset_mm", 2, false, p.sensor.offset_mm);
    const double plane_z = finite_number(member(sensor, "sensor", "plane_z_mm"), "sensor.plane_z_mm");

    const Json& depth = member(root, "", "depth_map");
    if (depth.is_string())
        out->depth_map = depth.get<std::string>();
    else if (!depth.is_null())
        refuse("depth_map", "a file name or null", depth);

    // Sampling and radiometry (sensor.radiometry) do not change where points image; any legal
    // value will do, and the defaults are.
    p.sampling = SamplingParams();

    const std::string problem = check_camera(p);
    if (!problem.empty())
        throw FieldError("the camera described is invalid: " + problem);
    out->model = with_film(make_camera(p), out->width, out->height);
    const PlenopticCamera& m = out->model;

    // Derived values must agree with what the parameters give.
    check_close("sensor.plane_z_mm", plane_z, m.sensor.z_mm, std::fabs(m.sensor.z_mm) + 1,
                "the distances (main_lens.distance_mm, microlens_array.distance_mm, translate_mm)");
    double principal[2];
    numbers(root, "", "principal_point_px", 2, false, principal);
    const Vec2 pp = m.sensor.principal_point_px();
    check_close("principal_point_px[0]", principal[0], pp.x, out->width + 1.0, "image.width and sensor.offset_mm");
    check_close("principal_point_px[1]", principal[1], pp.y, out->height + 1.0, "image.height and sensor.offset_mm");
    const Json& lattice = member(root, "", "microimage_lattice");
    if (m.array.grid == GridType::None) {
        if (!lattice.is_null())
            refuse("microimage_lattice", "null when microlens_array is null", lattice);
    } else {
        // null only where the writer writes null: a lattice whose numbers overflow (absurd poses).
        if (lattice.is_null() && !microimage_lattice(m).valid)
            return;
        if (!lattice.is_object())
            refuse("microimage_lattice", "an object (the file has a microlens array)", lattice);
        double origin[2];
        numbers(lattice, "microimage_lattice", "origin_px", 2, false, origin);
        const MicroimageCentre centre = microimage_centre_px(m, LensIndex{0, 0});
        if (centre.valid) {
            const double scale = out->width + out->height + 1.0;
            check_close("microimage_lattice.origin_px[0]", origin[0], centre.u, scale, "the lens parameters");
            check_close("microimage_lattice.origin_px[1]", origin[1], centre.v, scale, "the lens parameters");
        }
    }
}

} // namespace

MetadataReading parse_metadata(const std::string& text, const std::string& folder)
{
    MetadataReading reading;
    Json root;
    try {
        // Strict JSON: no comments; invalid UTF-8 and lone surrogates are parse errors.
        root = Json::parse(text, DuplicateKeyCheck());
    } catch (const FieldError& e) {
        reading.error = e.what();
        return reading;
    } catch (const Json::exception& e) {
        reading.error = "not valid JSON (" + parse_message(e.what()) + ")";
        return reading;
    }
    try {
        read_all(root, &reading.metadata, folder);
        return reading;
    } catch (const FieldError& e) {
        reading.error = e.what();
    } catch (const Json::exception& e) {  // not expected: every access above checks its type
        reading.error = "unexpected value (" + parse_message(e.what()) + ")";
    }
    reading.metadata = RenderMetadata();  // nothing half-read on refusal
    return reading;
}

MetadataReading read_metadata_file(const std::string& path)
{
    std::ifstream in(path.c_str(), std::ios::binary);
    MetadataReading reading;
    if (!in) {
        reading.error = "cannot open the metadata file";
        return reading;
    }
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) {
        reading.error = "cannot read the metadata file";
        return reading;
    }
    const std::size_t slash = path.find_last_of('/');
    return parse_metadata(text.str(), slash == std::string::npos ? std::string(".") : path.substr(0, slash));
}

OpticsPoint world_to_optics_mm(const RenderMetadata& md, Vec3 world)
{
    const CameraFrame& f = md.frame;
    const Vec3 r = f.right, u = f.up, d = f.direction;
    const Vec3 w = world - f.location;
    // Cramer's rule for x r + y u + z d = w.
    const double det = dot(r, cross(u, d));
    if (!(det != 0) || !std::isfinite(det))
        return OpticsPoint{Vec3{0, 0, 0}, false};
    const double x = dot(w, cross(u, d)) / det;
    const double y = dot(r, cross(w, d)) / det;
    const double z = dot(r, cross(u, w)) / det;
    const Vec3 optics{x * md.model.mm_per_unit, y * md.model.mm_per_unit, z * md.model.mm_per_unit};
    return OpticsPoint{optics, is_finite(optics)};
}

std::vector<PixelHit> project_world_point(const RenderMetadata& md, Vec3 world)
{
    const OpticsPoint optics = world_to_optics_mm(md, world);
    if (!optics.valid)
        return std::vector<PixelHit>();
    return md.model.project(optics.mm);
}

} // namespace plenoptic
