// SPDX-License-Identifier: AGPL-3.0-or-later
// The glass of a lens: its index of refraction at a wavelength. A medium is given by its index at
// the helium d line (n_d, what every lens file holds) and, when it disperses, either its Abbe
// number V_d (the two-term model below) or the six Sellmeier coefficients of a glass catalogue.
// Pure optics, no POV-Ray dependency. This is the one place an index at a wavelength is worked
// out: a trace at a wavelength builds its lens with index_at (prescription_at_wavelength).

#ifndef PLENOPTIC_GLASS_H
#define PLENOPTIC_GLASS_H

#include <string>

namespace plenoptic {

// The Fraunhofer lines by which glass catalogues give dispersion (nm): F (hydrogen), d (helium),
// C (hydrogen). n_F - n_C is the principal dispersion, V_d = (n_d - 1) / (n_F - n_C).
const double kLineFNm = 486.1327;
const double kLineDNm = 587.5618;
const double kLineCNm = 656.2725;

// The wavelengths a render may trace (nm): the checks below hold over this range.
const double kVisibleMinNm = 380;
const double kVisibleMaxNm = 720;

// Abbe numbers accepted: wider than any optical glass, crystal or plastic (about 17 for the
// densest flints to 95 for calcium fluoride), narrow enough to refuse an index or a typing slip
// written in the Abbe column.
const double kAbbeMin = 5;
const double kAbbeMax = 150;

// A Sellmeier index written with the d-line index (the lens file's or the ior keyword's, which a
// render without spectral sampling uses) must agree with it within this: catalogues print n_d to
// 5 decimals and patents often to 3.
const double kSellmeierNdTolerance = 5e-4;

// How a medium disperses. Neither model: it does not (its index is n_d at every wavelength).
struct Glass {
    double abbe = 0;                          // V_d; 0: no two-term model
    bool sellmeier = false;                   // the Sellmeier terms below hold
    double sellmeier_b[3] = {0, 0, 0};        // B1, B2, B3 (dimensionless)
    double sellmeier_c_um2[3] = {0, 0, 0};    // C1, C2, C3 in µm² (as catalogues print them)
    bool dispersive() const { return abbe != 0 || sellmeier; }
};

// The two-term model from n_d and V_d, lambda in nm:
//   n(lambda) = n_d + (n_d - 1) / V_d * (523655 / lambda^2 - 1.5168).
// It returns n_d at the d line (to 3.5e-5 of (n_d - 1) / V_d) and n_F - n_C = (n_d - 1) / V_d
// (to 2e-5 of it).
double two_term_index(double n_d, double abbe, double wavelength_nm);

// (n(lambda) - 1) / (n_d - 1) of the two-term model, 1 + (523655 / lambda^2 - 1.5168) / V_d: by
// how much a thin element's power (which is proportional to n - 1) changes from the d line's; 1
// for V_d = 0 (no dispersion). It does not depend on n_d.
double two_term_power_ratio(double abbe, double wavelength_nm);

// The Sellmeier formula n^2 = 1 + sum B_i lambda^2 / (lambda^2 - C_i), lambda in µm; NaN where
// n^2 < 0.
double sellmeier_index(const Glass& glass, double wavelength_nm);

// The index of a medium of d-line index n_d and this glass at the wavelength: n_d when it does
// not disperse, else the Sellmeier formula if given, else the two-term model.
double index_at(double n_d, const Glass& glass, double wavelength_nm);

// "" when the Abbe number is 0 (no dispersion) or within [kAbbeMin, kAbbeMax], else why not
// (the message names the value and the allowed range).
std::string check_abbe(double abbe);

// "" when the glass of a medium of d-line index n_d can be traced, else why not: a two-term
// model and Sellmeier terms together, an Abbe number out of range, a Sellmeier term that is not
// finite, a C_i (a resonance, lambda_i^2) within the traced wavelengths' squares, an index below
// 1 (or not a number) at some wavelength from kVisibleMinNm to kVisibleMaxNm (checked at every
// nm), a Sellmeier index at the d line more than kSellmeierNdTolerance from n_d.
std::string check_glass(double n_d, const Glass& glass);

} // namespace plenoptic

#endif
