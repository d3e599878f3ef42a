// SPDX-License-Identifier: AGPL-3.0-or-later
// Dispersion: the two-term model and the Sellmeier formula against a glass catalogue's published
// indices, the refusals of glasses a render cannot trace, a lens file's Abbe column, the focus
// at the F, d and C lines of a singlet against a paraxial ray trace written here and against the
// thin lens's f / V_d, and a cemented achromat against a singlet.
//
// Published figures (facts, transcribed): SCHOTT's optical glass data sheets, N-BK7 (n_d 1.51680,
// V_d 64.17, n_F 1.52238, n_C 1.51432; Sellmeier B1 1.03961212, B2 0.231792344,
// B3 1.01046945, C1 0.00600069867, C2 0.0200179144, C3 103.560653 µm²) and N-F2 (n_d 1.62004,
// V_d 36.37).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "plenoptic/array/array_params.h"
#include "plenoptic/camera/params.h"
#include "plenoptic/core/json.h"
#include "plenoptic/lens/glass.h"
#include "plenoptic/lens/main_lens.h"
#include "plenoptic/lens/prescription.h"

namespace plenoptic {
namespace {

const double kBk7Nd = 1.51680, kBk7Vd = 64.17, kBk7NF = 1.52238, kBk7NC = 1.51432;
const double kF2Nd = 1.62004, kF2Vd = 36.37;

Glass bk7_sellmeier()
{
    Glass g;
    g.sellmeier = true;
    const double b[3] = {1.03961212, 0.231792344, 1.01046945};
    const double c[3] = {0.00600069867, 0.0200179144, 103.560653};
    for (int i = 0; i < 3; ++i) {
        g.sellmeier_b[i] = b[i];
        g.sellmeier_c_um2[i] = c[i];
    }
    return g;
}

Glass abbe(double v)
{
    Glass g;
    g.abbe = v;
    return g;
}

TEST(Glass, TwoTermModelAgainstTheCatalogueForNBK7)
{
    // The model knows n_d and V_d only; N-BK7's published n_F and n_C differ from it by its
    // error, seen 5.0e-5 at F and 5.6e-5 at C: within 1e-4.
    EXPECT_NEAR(two_term_index(kBk7Nd, kBk7Vd, kLineFNm), kBk7NF, 1e-4);
    EXPECT_NEAR(two_term_index(kBk7Nd, kBk7Vd, kLineCNm), kBk7NC, 1e-4);
    // What the model is built to give: n_d at the d line, and the principal dispersion
    // (n_d - 1) / V_d (its constants hold these to 3.5e-5 and 2e-5 of the dispersion).
    const double dispersion = (kBk7Nd - 1) / kBk7Vd;
    EXPECT_NEAR(two_term_index(kBk7Nd, kBk7Vd, kLineDNm), kBk7Nd, 3.5e-5 * dispersion);
    EXPECT_NEAR(two_term_index(kBk7Nd, kBk7Vd, kLineFNm) - two_term_index(kBk7Nd, kBk7Vd, kLineCNm), dispersion,
                2e-5 * dispersion);
    // Normal dispersion: the index falls with the wavelength.
    EXPECT_GT(two_term_index(kBk7Nd, kBk7Vd, 400), two_term_index(kBk7Nd, kBk7Vd, 700));
}

TEST(Glass, SellmeierAgainstTheCatalogueForNBK7)
{
    const Glass g = bk7_sellmeier();
    EXPECT_NEAR(sellmeier_index(g, kLineFNm), kBk7NF, 1e-5);
    EXPECT_NEAR(sellmeier_index(g, kLineDNm), kBk7Nd, 1e-5);
    EXPECT_NEAR(sellmeier_index(g, kLineCNm), kBk7NC, 1e-5);
    // index_at takes the Sellmeier terms over the written n_d; a medium without glass keeps n_d.
    EXPECT_EQ(index_at(1.5168, g, 500), sellmeier_index(g, 500));
    EXPECT_EQ(index_at(1.5168, abbe(64.17), 500), two_term_index(1.5168, 64.17, 500));
    EXPECT_EQ(index_at(1.5168, Glass(), 400), 1.5168);
    EXPECT_EQ(check_glass(kBk7Nd, g), "");
}

TEST(Glass, RefusesWhatCannotBeTraced)
{
    EXPECT_EQ(check_glass(1.5, abbe(0)), "");
    EXPECT_EQ(check_glass(1.5, abbe(5)), "");
    EXPECT_EQ(check_glass(1.5, abbe(150)), "");
    for (double v : {4.99, 150.01, -64.17, 1.5168}) {
        const std::string message = check_glass(1.5, abbe(v));
        EXPECT_NE(message.find("outside 5 to 150"), std::string::npos) << v << ": " << message;
    }
    Glass both = bk7_sellmeier();
    both.abbe = 64.17;
    EXPECT_NE(check_glass(kBk7Nd, both).find("not both"), std::string::npos);
    // C written in nm² or nm instead of µm²: a resonance inside 380-720 nm, refused by name.
    Glass in_range = bk7_sellmeier();
    in_range.sellmeier_c_um2[1] = 0.25;  // 500 nm
    EXPECT_NE(check_glass(kBk7Nd, in_range).find("C2 = 0.25 µm² is a resonance at 500 nm"), std::string::npos)
        << check_glass(kBk7Nd, in_range);
    Glass infinite = bk7_sellmeier();
    infinite.sellmeier_b[2] = INFINITY;
    EXPECT_NE(check_glass(kBk7Nd, infinite).find("finite"), std::string::npos);
    // An index below 1 somewhere in 380-720 nm.
    Glass low;
    low.sellmeier = true;
    low.sellmeier_b[0] = -0.5;
    low.sellmeier_c_um2[0] = 0.01;
    EXPECT_NE(check_glass(0.70, low).find("must be >= 1"), std::string::npos) << check_glass(0.70, low);
    // Sellmeier terms of another glass than the written index.
    EXPECT_NE(check_glass(1.6, bk7_sellmeier()).find("give n_d = 1.5168"), std::string::npos)
        << check_glass(1.6, bk7_sellmeier());
    EXPECT_EQ(check_glass(kBk7Nd + 4e-4, bk7_sellmeier()), "");
}

TEST(Glass, LensFileAbbeColumn)
{
    // Four or five numbers a row; the fifth is V_d, 0 or absent: no dispersion.
    const ParsedPrescription p = parse_lens_file("0 2 0 10\n60 5 1.5168 20 64.17\n-60 40 1 20 0\n");
    ASSERT_FALSE(p.error.any()) << p.error.message;
    EXPECT_EQ(p.prescription.surfaces[1].glass.abbe, 64.17);
    EXPECT_FALSE(p.prescription.surfaces[2].glass.dispersive());
    EXPECT_TRUE(dispersive(p.prescription));
    EXPECT_FALSE(dispersive(parse_lens_file("0 2 0 10\n60 5 1.5168 20\n-60 40 1 20\n").prescription));

    const struct {
        const char* text;
        int line;
        const char* says;
    } refused[] = {
        {"0 2 0 10\n60 5 1.5168 20 2\n-60 40 1 20\n", 2, "surface 2: the Abbe number V_d 2 is outside 5 to 150"},
        {"0 2 0 10\n60 5 1.5168 20 64.17 1 1 2 3 4 5 6 7 8 9\n-60 40 1 20\n", 2, "this one has 15"},
        {"0 2 0 10 30\n60 5 1.5168 20\n-60 40 1 20\n", 1, "the stop does not refract; it takes no Abbe number"},
        {"0 2 0 10\n60 5 1.5168 20\n-60 40 1 20 64\n", 3, "air (index 1), which does not disperse"},
        {"0 2 0 10\n60 5 1.5168 20 nan\n-60 40 1 20\n", 2, "is not a finite number"},
    };
    for (const auto& r : refused) {
        const ParsedPrescription bad = parse_lens_file(r.text);
        EXPECT_EQ(bad.error.line, r.line) << r.text;
        EXPECT_NE(bad.error.message.find(r.says), std::string::npos) << bad.error.message;
    }
}

// A paraxial ray trace written out here (heights and angles surface by surface, not the
// library's transfer matrices): the back focal distance and EFL of a ray parallel to the axis at
// height 1, the indices given per medium.
struct Focus {
    double efl, bfd;
};
Focus trace_parallel_ray(const double* radius, const double* thickness, const double* index, int count)
{
    double y = 1, u = 0, n = 1;
    for (int i = 0; i < count; ++i) {
        const double power = radius[i] == 0 ? 0 : (index[i] - n) / radius[i];
        u = (n * u - y * power) / index[i];
        n = index[i];
        if (i + 1 < count)
            y += thickness[i] * u;
    }
    return Focus{-1 / u, -y / u};
}

std::string row(double radius, double thickness, double n, double aperture, double v)
{
    char text[200];
    std::snprintf(text, sizeof text, "%.17g %.17g %.17g %.17g %.17g\n", radius, thickness, n, aperture, v);
    return text;
}

TEST(Glass, SingletFocusAtTheLinesAgainstAParaxialTrace)
{
    // A thick N-BK7 biconvex lens behind a stop (the stop is flat: it changes no focus).
    const double R[2] = {50, -80}, t = 8;
    const ParsedPrescription p =
        parse_lens_file(row(0, 3, 0, 20, 0) + row(R[0], t, kBk7Nd, 30, kBk7Vd) + row(R[1], 60, 1, 30, 0));
    ASSERT_FALSE(p.error.any()) << p.error.message;
    const ChromaticFocus focus = chromatic_focus(p.prescription);
    ASSERT_TRUE(focus.valid);
    const double wavelengths[3] = {486.1327, 587.5618, 656.2725};
    double bfd[3];
    for (int k = 0; k < 3; ++k) {
        const double l = wavelengths[k];
        const double n = kBk7Nd + (kBk7Nd - 1) / kBk7Vd * (523655 / (l * l) - 1.5168);
        const double radius[2] = {R[0], R[1]}, thickness[2] = {t, 0}, index[2] = {n, 1};
        const Focus f = trace_parallel_ray(radius, thickness, index, 2);
        EXPECT_EQ(focus.lines[k].wavelength_nm, l);
        EXPECT_NEAR(focus.lines[k].efl_mm, f.efl, 1e-10 * f.efl);
        EXPECT_NEAR(focus.lines[k].bfd_mm, f.bfd, 1e-10 * f.efl);
        bfd[k] = f.bfd;
    }
    EXPECT_NEAR(focus.longitudinal_colour_mm, bfd[0] - bfd[2], 1e-9);
    EXPECT_LT(focus.longitudinal_colour_mm, 0);  // blue focuses nearer: undercorrected
    EXPECT_STREQ(focus.lines[0].line, "F");
    EXPECT_STREQ(focus.lines[2].line, "C");
}

TEST(Glass, ThinSingletLongitudinalColourIsFocalLengthOverAbbe)
{
    // A weak, very thin biconvex lens (t / f = 3e-5). A thin lens of power K (n - 1) focuses at
    // 1 / (K (n - 1)), so its longitudinal colour is exactly (1 / (n_F - 1) - 1 / (n_C - 1)) / K;
    // to first order in the dispersion that is -f / V_d, and the next order is
    // (n_F + n_C - 2 n_d) / (n_d - 1) = 0.398 / V_d of it for the two-term model (measured 0.0062 at
    // V_d 64.17).
    for (double v : {25.0, 64.17, 90.0}) {
        const double R = 1000, t = 0.03;
        const ParsedPrescription p = parse_lens_file(row(0, 0.5, 0, 8, 0) + row(R, t, kBk7Nd, 10, v) + row(-R, 900, 1, 10, 0));
        ASSERT_FALSE(p.error.any()) << p.error.message;
        const ChromaticFocus focus = chromatic_focus(p.prescription);
        ASSERT_TRUE(focus.valid);
        const double f = focus.lines[1].efl_mm;
        EXPECT_NEAR(f, R / (2 * (kBk7Nd - 1)), 1e-3 * f);
        const double nF = kBk7Nd + (kBk7Nd - 1) / v * (523655 / (486.1327 * 486.1327) - 1.5168);
        const double nC = kBk7Nd + (kBk7Nd - 1) / v * (523655 / (656.2725 * 656.2725) - 1.5168);
        const double K = 2 / R;
        EXPECT_NEAR(focus.longitudinal_colour_mm, (1 / (nF - 1) - 1 / (nC - 1)) / K, 1e-4 * f / v) << "V_d " << v;
        EXPECT_NEAR(focus.longitudinal_colour_mm, -f / v, 0.45 / v * f / v) << "V_d " << v;
    }
}

TEST(Glass, CementedAchromatHasFarLessLongitudinalColourThanASinglet)
{
    // f = 100 mm: thin-lens achromat condition phi1 / V1 + phi2 / V2 = 0, phi1 + phi2 = phi;
    // an equiconvex N-BK7 crown cemented to an N-F2 flint.
    const double f = 100, phi = 1 / f;
    const double phi1 = phi * kBk7Vd / (kBk7Vd - kF2Vd), phi2 = -phi * kF2Vd / (kBk7Vd - kF2Vd);
    const double r1 = 2 * (kBk7Nd - 1) / phi1, r2 = -r1;
    const double r3 = 1 / (1 / r2 - phi2 / (kF2Nd - 1));
    const ParsedPrescription achromat = parse_lens_file(row(0, 1, 0, 20, 0) + row(r1, 4, kBk7Nd, 25, kBk7Vd) +
                                                        row(r2, 1.5, kF2Nd, 25, kF2Vd) + row(r3, 90, 1, 25, 0));
    ASSERT_FALSE(achromat.error.any()) << achromat.error.message;
    const double rs = 2 * (kBk7Nd - 1) * f;
    const ParsedPrescription singlet =
        parse_lens_file(row(0, 1, 0, 20, 0) + row(rs, 4, kBk7Nd, 25, kBk7Vd) + row(-rs, 90, 1, 25, 0));
    ASSERT_FALSE(singlet.error.any()) << singlet.error.message;
    const ChromaticFocus a = chromatic_focus(achromat.prescription), s = chromatic_focus(singlet.prescription);
    ASSERT_TRUE(a.valid && s.valid);
    EXPECT_NEAR(a.lines[1].efl_mm, f, 0.03 * f);
    EXPECT_NEAR(s.lines[1].efl_mm, f, 0.03 * f);
    EXPECT_NEAR(s.longitudinal_colour_mm, -f / kBk7Vd, 0.05 * f / kBk7Vd);
    EXPECT_LT(std::fabs(a.longitudinal_colour_mm), 0.1 * std::fabs(s.longitudinal_colour_mm))
        << "achromat " << a.longitudinal_colour_mm << " mm, singlet " << s.longitudinal_colour_mm << " mm";
    std::printf("longitudinal colour (F - C), f = 100 mm: singlet %.5f mm, achromat %.5f mm\n",
                s.longitudinal_colour_mm, a.longitudinal_colour_mm);
}

TEST(Glass, AtAWavelengthEachMediumHasItsIndex)
{
    const ParsedPrescription p = parse_lens_file("0 2 0 10\n60 5 1.5168 20 64.17\n-60 40 1 20\n");
    ASSERT_FALSE(p.error.any());
    const Prescription blue = prescription_at_wavelength(p.prescription, 450);
    EXPECT_EQ(blue.surfaces[1].ior, two_term_index(1.5168, 64.17, 450));
    EXPECT_FALSE(dispersive(blue));
    EXPECT_EQ(blue.surfaces[2].ior, 1);
    EXPECT_EQ(blue.surfaces[0].ior, 0);
}

// A dispersing lens's metadata: its surfaces' glass and its focus at the lines; a lens without
// dispersion writes neither.
TEST(Glass, MetadataOfADispersingLens)
{
    const ParsedPrescription plain = parse_lens_file("0 2 0 10\n60 5 1.5168 20\n-60 40 1 20\n");
    const ParsedPrescription glass = parse_lens_file("0 2 0 10\n60 5 1.5168 20 64.17\n-60 40 1 20\n");
    ASSERT_FALSE(plain.error.any() || glass.error.any());
    const LensPlacement at{55, false, 0, ""};
    const MetadataJson without = main_lens_metadata(make_prescription_lens(plain.prescription, 0, true, 55).get(), at);
    const MetadataJson with = main_lens_metadata(make_prescription_lens(glass.prescription, 0, true, 55).get(), at);
    EXPECT_FALSE(without["paraxial"].contains("lines"));
    EXPECT_FALSE(without["paraxial"].contains("longitudinal_colour_mm"));
    for (const MetadataJson& s : without["prescription"]["surfaces"])
        EXPECT_FALSE(s.contains("abbe_number") || s.contains("sellmeier"));
    EXPECT_EQ(with["prescription"]["surfaces"][1]["abbe_number"], 64.17);
    EXPECT_FALSE(with["prescription"]["surfaces"][2].contains("abbe_number"));
    const ChromaticFocus focus = chromatic_focus(glass.prescription);
    EXPECT_EQ(with["paraxial"]["lines"]["F"]["back_focal_distance_mm"].get<double>(), focus.lines[0].bfd_mm);
    EXPECT_EQ(with["paraxial"]["lines"]["C"]["wavelength_nm"].get<double>(), kLineCNm);
    EXPECT_EQ(with["paraxial"]["longitudinal_colour_mm"].get<double>(), focus.longitudinal_colour_mm);
    // Everything else as without dispersion (the render without spectral sampling uses n_d).
    MetadataJson trimmed = with;
    trimmed["paraxial"].erase("lines");
    trimmed["paraxial"].erase("longitudinal_colour_mm");
    trimmed["prescription"]["surfaces"][1].erase("abbe_number");
    EXPECT_EQ(trimmed, without);
}

// Dispersing microlenses: their Abbe number is checked with the array and written to its metadata.
TEST(Glass, MicrolensAbbeNumber)
{
    ArrayParams a;
    a.given = true;
    a.grid = GridType::Hexagonal;
    a.has_pitch = true;
    a.pitch_mm = 0.1;
    a.has_lens = true;
    a.lens = MicrolensType::ThinLens;
    a.focal_length_count = 1;
    a.focal_lengths_mm[0] = 0.4;
    a.has_distance = true;
    a.distance_mm = 0.4;
    EXPECT_EQ(check_array(a), "");
    const MicrolensArray plain = make_microlens_array(a, -50);
    EXPECT_FALSE(plain.metadata(a.rotate_deg, a.translate_mm).contains("abbe_number"));
    a.abbe = 58;
    EXPECT_EQ(check_array(a), "");
    const MicrolensArray glass = make_microlens_array(a, -50);
    EXPECT_EQ(glass.abbe, 58);
    MetadataJson written = glass.metadata(a.rotate_deg, a.translate_mm);
    EXPECT_EQ(written["abbe_number"], 58);
    written.erase("abbe_number");
    EXPECT_EQ(written, plain.metadata(a.rotate_deg, a.translate_mm));
    a.abbe = 200;
    EXPECT_NE(check_array(a).find("microlens_array abbe: the Abbe number V_d 200 is outside 5 to 150"), std::string::npos)
        << check_array(a);
    a.abbe = 40;
    a.lens = MicrolensType::Pinhole;
    a.focal_length_count = 0;
    EXPECT_NE(check_array(a).find("a pinhole has no glass"), std::string::npos) << check_array(a);
}

} // namespace
} // namespace plenoptic
