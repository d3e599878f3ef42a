// SPDX-License-Identifier: AGPL-3.0-or-later
// The lens catalogue (lenses/, installed with the program): every lens file parses
// without a refusal, and each design's paraxial EFL and back focal distance (and f-number, where
// the source states one) match the values published with the design, and its EFL the nominal
// focal length the file was scaled to. The values are written here, each with its source, and
// never taken from the file itself; see lenses/README.md. Where the source prints a table but
// no EFL or back focus, the row holds those of an independent paraxial trace of the published
// table (not of the file), and says so: a file that mistranscribes a row fails.
//
// The folder is the source tree's lenses/ (PLENOPTIC_LENSES_DIR, set by CMakeLists.txt); the
// environment variable PLENOPTIC_LENSES_DIR, when set, points the test at another folder (an
// installed share/povray-plenoptic/lenses, for instance).

#include <gtest/gtest.h>

#include <dirent.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "plenoptic/lens/prescription.h"

#ifndef PLENOPTIC_LENSES_DIR
#error "PLENOPTIC_LENSES_DIR must name the lenses/ folder (see CMakeLists.txt)"
#endif

namespace plenoptic {
namespace {

// The values printed with one design, in the file's scale (published value times the scale
// factor the file's header states). A tolerance is the rounding of the published figure: half
// a unit in its last printed digit, times the scale factor, unless the row states a wider one
// and why (glass indices the source does not print, an image plane that is not the paraxial focus).
// The nominal focal length is the one the file's name and scaling promise (a published table
// normalised to f = 100 and scaled by a round factor): its tolerance says how far the scaled
// table's EFL may lie from it, and the row says how far it does.
struct Published {
    const char* file;      // name in lenses/
    const char* source;    // patent and example, or book and page
    double efl_mm, efl_tolerance_mm;
    double bfd_mm, bfd_tolerance_mm;
    double f_number, f_number_tolerance;  // f_number 0: the source states none
    double nominal_efl_mm, nominal_tolerance_mm;
};

// A printed f-number is a marking of the third-stop series (2, 2.2, 2.5, 2.8, ... 5.6), the
// nearest to the design's: the paraxial f-number at the printed stop lies within a sixth of a
// stop of it, a factor 2^(1/12).
double sixth_of_a_stop(double printed) { return printed * (std::pow(2.0, 1.0 / 12.0) - 1.0); }

// One row a lens file.
const std::vector<Published> kPublished = {
    // Laikin, Lens Design, 4th ed., Table 8.1, scaled by 22 / 1.181. Printed EFL 1.181 -> 22 mm.
    // Not the rounding of the figure but 0.1% (0.022 mm): the book names glasses only, and with
    // Schott's n_d (the file's index) the EFL is 0.05% longer than printed (the printed value
    // matches the e line). Back focus: the printed distance from the last surface to the image,
    // 2.2253 -> 41.4533 mm, is the book's image plane, 0.17% in front of the paraxial focus
    // (n_d: 2.2291 -> 41.524 mm); tolerance 0.2% (0.083 mm). f/3.5 as printed (the stop's
    // printed diameter 0.647 gives f/3.499), to the rounding of the printed figure.
    {"wide_angle_22mm_laikin_f3.5.dat", "Laikin, Lens Design, 4th ed. (CRC), Table 8.1, f/3.5 inverted telephoto",
     22.0, 0.022, 2.2253 * 22.0 / 1.181, 0.002 * 2.2253 * 22.0 / 1.181, 3.5, 0.05,
     // Nominal 22 mm: the printed EFL scaled, so the same figure (the file's EFL is 22.011 mm).
     22.0, 0.022},

    // The three below: W. J. Smith, Modern Lens Design (McGraw-Hill, 1992), as pbrt-v4's scene
    // repository distributes the tables, scaled by a round factor from the book's f = 100. The
    // book's tables print no back focus (their last thickness is 0), and the f = 100 tables do
    // not trace to exactly 100. EFL and BFD are therefore an independent trace of the published
    // scaled table (a y-nu ray-transfer-matrix product in Python over the table's rows, agreeing
    // with the tests' reference tracer tests/pylib/plenoptic_testing/lens_tracer.py to 1e-9 mm),
    // given to 0.0001 mm: tolerance half a unit of that digit. The f-number: the printed
    // marking at the printed stop (sixth_of_a_stop). The nominal focal length: within 1 %.

    // Double-Gauss, Tronnier, US 2,673,491, MLD p. 312, x 0.5. EFL 50.3582 mm: 0.72 % (0.358 mm)
    // above the nominal 50 mm (the book's table traces to 100.716 for its 100). Printed stop
    // 17.1 mm: f/2.030 (printed f/2). At full aperture surface 3's rim, not the stop, limits the
    // axial beam to first order (the fastest f_number it accepts is 2.073 focused at infinity).
    {"double_gauss_50mm_tronnier_f2.dat", "Tronnier, US 2,673,491; Smith, Modern Lens Design p. 312, f/2",
     50.3582, 0.00005, 36.1059, 0.00005, 2.0, sixth_of_a_stop(2.0), 50.0, 0.5},

    // Telephoto, Sigler, MLD p. 175 (printed EFL 254 mm, F/5.6), x 2.5. EFL 249.5666 mm: 0.17 %
    // (0.433 mm) below the nominal 250 mm; the printed 254 mm is 10 in, the design before the
    // book's normalisation (the f = 100 table traces to 99.827). Printed stop 40.5 mm: f/5.423.
    {"telephoto_250mm_sigler_f5.6.dat", "Sigler telephoto; Smith, Modern Lens Design p. 175, F/5.6",
     249.5666, 0.00005, 105.0704, 0.00005, 5.6, sixth_of_a_stop(5.6), 250.0, 2.5},

    // Fisheye, Muller, US 4,525,038 (16 mm f/4, 155.9 degree field), MLD p. 164, x 0.1. EFL
    // 9.9914 mm: 0.09 % (0.009 mm) below the nominal 10 mm. Printed stop 6.08 mm: f/3.947. The
    // field is not checked here: paraxial data describe the axis, and at 78 degrees from it a
    // fisheye's image height has nothing to do with f tan(angle).
    {"fisheye_10mm_muller_f4.dat", "Muller, US 4,525,038; Smith, Modern Lens Design p. 164, f/4",
     9.9914, 0.00005, 23.1605, 0.00005, 4.0, sixth_of_a_stop(4.0), 10.0, 0.1},
};

std::string lenses_dir()
{
    const char* env = std::getenv("PLENOPTIC_LENSES_DIR");
    return env && *env ? std::string(env) : std::string(PLENOPTIC_LENSES_DIR);
}

// The *.dat files of the folder, sorted.
std::vector<std::string> lens_files(const std::string& dir)
{
    std::vector<std::string> names;
    DIR* d = opendir(dir.c_str());
    if (!d)
        return names;
    while (const dirent* e = readdir(d)) {
        const std::string name = e->d_name;
        if (name.size() > 4 && name.compare(name.size() - 4, 4, ".dat") == 0)
            names.push_back(name);
    }
    closedir(d);
    std::sort(names.begin(), names.end());
    return names;
}

bool read_text(const std::string& path, std::string* text)
{
    std::ifstream in(path.c_str(), std::ios::binary);
    if (!in)
        return false;
    std::ostringstream s;
    s << in.rdbuf();
    *text = s.str();
    return true;
}

const Published* published_for(const std::string& file)
{
    for (const Published& p : kPublished)
        if (file == p.file)
            return &p;
    return nullptr;
}

TEST(LensCatalogue, FolderExists)
{
    DIR* d = opendir(lenses_dir().c_str());
    ASSERT_NE(d, nullptr) << "no folder " << lenses_dir();
    closedir(d);
}

TEST(LensCatalogue, EveryLensFileParsesWithoutARefusal)
{
    const std::vector<std::string> files = lens_files(lenses_dir());
    if (files.empty())
        GTEST_SKIP() << "no lens file in " << lenses_dir() << " yet";
    for (const std::string& name : files) {
        std::string text;
        ASSERT_TRUE(read_text(lenses_dir() + "/" + name, &text)) << name;
        const ParsedPrescription p = parse_lens_file(text);
        EXPECT_FALSE(p.error.any()) << name << ", line " << p.error.line << ": " << p.error.message;
    }
}

// A file cannot join the catalogue without its published values, nor a row outlive its file.
TEST(LensCatalogue, EveryLensFileHasItsPublishedValues)
{
    const std::vector<std::string> files = lens_files(lenses_dir());
    if (files.empty() && kPublished.empty())
        GTEST_SKIP() << "no lens file in " << lenses_dir() << " yet";
    for (const std::string& name : files)
        EXPECT_NE(published_for(name), nullptr) << name << " has no row in kPublished";
    for (const Published& p : kPublished) {
        const bool present = std::find(files.begin(), files.end(), std::string(p.file)) != files.end();
        EXPECT_TRUE(present) << p.file << " (" << p.source << ") is not in " << lenses_dir();
    }
}

TEST(LensCatalogue, ParaxialDataMatchThePublishedValues)
{
    if (kPublished.empty())
        GTEST_SKIP() << "no published values yet";
    for (const Published& pub : kPublished) {
        SCOPED_TRACE(std::string(pub.file) + ", " + pub.source);
        std::string text;
        if (!read_text(lenses_dir() + "/" + pub.file, &text)) {
            ADD_FAILURE() << "cannot read the file";
            continue;
        }
        const ParsedPrescription parsed = parse_lens_file(text);
        if (parsed.error.any()) {
            ADD_FAILURE() << "refused: " << parsed.error.message;
            continue;
        }
        const ParaxialData d = paraxial_data(parsed.prescription);
        if (!d.valid) {
            ADD_FAILURE() << "no paraxial data (afocal?)";
            continue;
        }
        EXPECT_NEAR(d.efl_mm, pub.efl_mm, pub.efl_tolerance_mm) << "EFL";
        EXPECT_NEAR(d.bfd_mm, pub.bfd_mm, pub.bfd_tolerance_mm) << "back focal distance";
        EXPECT_NEAR(d.efl_mm, pub.nominal_efl_mm, pub.nominal_tolerance_mm) << "EFL against the nominal focal length";
        if (pub.f_number > 0) {
            EXPECT_NEAR(d.f_number, pub.f_number, pub.f_number_tolerance) << "f-number";
        }
    }
}

} // namespace
} // namespace plenoptic
