// SPDX-License-Identifier: AGPL-3.0-or-later
// Writes the plenoptic render metadata as JSON with a small writer of its own.

#include "plenoptic_metadata.h"

#include <cmath>
#include <cstdio>
#include <vector>

#include "plenoptic_optics.h"

namespace plenoptic {

namespace {

// Minimal JSON writer: objects one member per line, arrays of numbers on one line.
class JsonWriter {
public:
    void begin_object(bool one_line = false) { open('{', one_line); }
    void end_object() { close('}'); }
    void begin_array(bool one_line = true) { open('[', one_line); }
    void end_array() { close(']'); }

    void key(const char* name)
    {
        before_value();
        append_string(name);
        out_ += ": ";
        after_key_ = true;
    }

    void number(double value)
    {
        before_value();
        if (!std::isfinite(value)) {
            out_ += "null";  // JSON has no NaN or infinity
            return;
        }
        char buffer[40];
        std::snprintf(buffer, sizeof buffer, "%.17g", value);
        out_ += buffer;
    }

    void integer(long long value)
    {
        before_value();
        out_ += std::to_string(value);
    }

    void boolean(bool value)
    {
        before_value();
        out_ += value ? "true" : "false";
    }

    void null()
    {
        before_value();
        out_ += "null";
    }

    void string(const std::string& value)
    {
        before_value();
        append_string(value);
    }

    void numbers(const double* values, int count)
    {
        begin_array();
        for (int i = 0; i < count; ++i)
            number(values[i]);
        end_array();
    }

    std::string text() const { return out_ + "\n"; }

private:
    struct Level {
        bool object;
        bool one_line;
        bool empty;
    };

    void open(char bracket, bool one_line)
    {
        before_value();
        out_ += bracket;
        levels_.push_back(Level{bracket == '{', one_line, true});
    }

    void close(char bracket)
    {
        const Level level = levels_.back();
        levels_.pop_back();
        if (!level.empty && !level.one_line)
            newline();
        out_ += bracket;
    }

    void newline()
    {
        out_ += '\n';
        out_.append(2 * levels_.size(), ' ');
    }

    void before_value()
    {
        if (after_key_) {
            after_key_ = false;
            return;
        }
        if (levels_.empty())
            return;
        Level& level = levels_.back();
        if (!level.empty)
            out_ += level.one_line ? ", " : ",";
        if (!level.one_line)
            newline();
        level.empty = false;
    }

    void append_string(const std::string& value)
    {
        out_ += '"';
        for (unsigned char c : value) {
            if (c == '"' || c == '\\') {
                out_ += '\\';
                out_ += char(c);
            } else if (c < 0x20) {
                char buffer[8];
                std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
                out_ += buffer;
            } else {
                out_ += char(c);
            }
        }
        out_ += '"';
    }

    std::string out_;
    std::vector<Level> levels_;
    bool after_key_ = false;
};

const char* main_lens_name(MainLensType type)
{
    switch (type) {
    case MainLensType::ThinLens: return "thin_lens";
    case MainLensType::Pinhole: return "pinhole";
    default: return "none";
    }
}

void write_number_or_null(JsonWriter* json, const char* key, bool present, double value)
{
    json->key(key);
    if (present)
        json->number(value);
    else
        json->null();
}

void write_vector3(JsonWriter* json, const char* key, const double v[3])
{
    json->key(key);
    json->numbers(v, 3);
}

void write_main_lens(JsonWriter* json, const Model& m)
{
    const bool thin = m.main_lens == MainLensType::ThinLens;
    json->key("main_lens");
    json->begin_object();
    json->key("type");
    json->string(main_lens_name(m.main_lens));
    write_number_or_null(json, "focal_length_mm", thin, m.focal_length_mm);
    write_number_or_null(json, "aperture_mm", thin, m.aperture_mm);
    write_number_or_null(json, "f_number", thin, m.f_number);
    write_number_or_null(json, "distance_mm", m.main_lens != MainLensType::None, m.distance_mm);
    write_number_or_null(json, "focus_distance", m.has_focus_distance, m.focus_distance_units);
    json->end_object();
}

void write_array(JsonWriter* json, const Model& m, const CameraParams& params)
{
    json->key("microlens_array");
    if (m.grid == GridType::None) {
        json->null();
        return;
    }
    json->begin_object();
    json->key("grid");
    json->string(m.grid == GridType::Hexagonal ? "hexagonal" : "rectangular");
    json->key("lens");
    json->string(m.microlens == MicrolensType::ThinLens ? "thin_lens" : "pinhole");
    json->key("pitch_mm");
    json->number(m.pitch_mm);
    json->key("focal_lengths_mm");
    json->numbers(m.microlens_focal_mm, m.microlens == MicrolensType::ThinLens ? m.lens_type_count : 0);
    json->key("distance_mm");
    json->number(m.array_distance_mm);
    write_vector3(json, "rotate_deg", params.array.rotate_deg);
    write_vector3(json, "translate_mm", params.array.translate_mm);
    json->end_object();
}

void write_lattice(JsonWriter* json, const Model& m, const MicroimageLattice& lattice)
{
    json->key("microimage_lattice");
    if (!lattice.valid) {
        json->null();
        return;
    }
    const bool hexagonal = m.grid == GridType::Hexagonal;
    json->begin_object();
    json->key("origin_px");
    json->numbers(lattice.origin_px, 2);
    json->key("basis_px");
    json->begin_array();
    json->numbers(lattice.basis_a_px, 2);
    json->numbers(lattice.basis_b_px, 2);
    json->end_array();
    json->key("index_rule");
    json->string(hexagonal
                     ? "skew indices (k, l): hexagonal centres in the array are k*(p,0) + l*(p/2, p*sqrt(3)/2)"
                     : "skew indices (k, l): rectangular centres in the array are k*(p,0) + l*(0,p)");
    json->key("exact");
    json->boolean(lattice.exact);
    const int types = m.microlens == MicrolensType::ThinLens ? m.lens_type_count : 1;
    json->key("lens_types");
    json->integer(types);
    json->key("lens_type_rule");
    json->string(types == 3 ? "type(k, l) = (k - l) mod 3, focal_lengths_mm[type]" : "type(k, l) = 0");
    // Diameter of the main aperture's image behind a lens centre (the f-number-matched disc).
    write_number_or_null(json, "microimage_diameter_px", m.main_lens == MainLensType::ThinLens,
                         m.aperture_mm * effective_array_distance_mm(m) / effective_main_distance_mm(m) /
                             m.pixel_size_mm[0]);
    json->end_object();
}

void write_lftoolbox(JsonWriter* json, const MicroimageLattice& lattice)
{
    json->key("lftoolbox_lenslet_grid_model");
    if (!lattice.valid || !lattice.lftoolbox_valid) {
        json->null();
        return;
    }
    json->begin_object();
    json->key("HSpacing");
    json->number(lattice.h_spacing);
    json->key("VSpacing");
    json->number(lattice.v_spacing);
    json->key("HOffset");
    json->number(lattice.h_offset);
    json->key("VOffset");
    json->number(lattice.v_offset);
    json->key("Rot");
    json->number(lattice.rot);
    json->key("Orientation");
    json->string("horz");
    json->key("FirstPosShiftRow");
    if (lattice.first_pos_shift_row > 0)
        json->integer(lattice.first_pos_shift_row);
    else
        json->null();  // rectangular grid: LFToolbox's grid always shifts alternate rows
    json->key("UMax");
    json->integer(lattice.u_max);
    json->key("VMax");
    json->integer(lattice.v_max);
    json->end_object();
}

} // namespace

std::string metadata_json(const Model& m, const CameraParams& params, int W, int H, const CameraFrame& frame,
                          const std::string& depth_map_file)
{
    JsonWriter json;
    json.begin_object();
    json.key("format");
    json.string("povray-plenoptic-metadata");
    json.key("version");
    json.integer(1);

    json.key("image");
    json.begin_object();
    json.key("width");
    json.integer(W);
    json.key("height");
    json.integer(H);
    json.end_object();

    json.key("mm_per_unit");
    json.number(m.mm_per_unit);

    json.key("camera_frame");
    json.begin_object();
    write_vector3(&json, "location", frame.location);
    write_vector3(&json, "right", frame.right);
    write_vector3(&json, "up", frame.up);
    write_vector3(&json, "direction", frame.direction);
    json.end_object();

    write_main_lens(&json, m);
    write_array(&json, m, params);

    json.key("sensor");
    json.begin_object();
    json.key("pixel_size_mm");
    json.numbers(m.pixel_size_mm, 2);
    json.key("offset_mm");
    json.numbers(m.sensor_offset_mm, 2);
    json.key("plane_z_mm");
    json.number(m.sensor_z_mm);
    json.end_object();

    json.key("samples");
    json.begin_object(true);
    json.key("adaptive");
    json.boolean(m.adaptive);
    json.key("min");
    json.integer(m.samples_min);
    json.key("max");
    json.integer(m.samples_max);
    json.key("confidence");
    json.number(m.confidence);
    json.key("variance");
    json.number(m.variance);
    json.end_object();

    const Vec2 principal = principal_point_px(m, W, H);
    const double principal_px[2] = {principal.x, principal.y};
    json.key("principal_point_px");
    json.numbers(principal_px, 2);

    const MicroimageLattice lattice = microimage_lattice(m, W, H);
    write_lattice(&json, m, lattice);
    write_lftoolbox(&json, lattice);

    json.key("depth_map");
    if (depth_map_file.empty())
        json.null();
    else
        json.string(depth_map_file);

    json.end_object();
    return json.text();
}

} // namespace plenoptic
