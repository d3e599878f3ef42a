// SPDX-License-Identifier: AGPL-3.0-or-later
// The glass of a lens: its index at a wavelength (see the header).

#include "plenoptic/lens/glass.h"

#include <cmath>
#include <sstream>

#include "plenoptic/core/format.h"

namespace plenoptic {

double two_term_index(double n_d, double abbe, double wavelength_nm)
{
    return n_d + (n_d - 1) / abbe * (523655.0 / (wavelength_nm * wavelength_nm) - 1.5168);
}

double two_term_power_ratio(double abbe, double wavelength_nm)
{
    if (abbe == 0)
        return 1;
    return 1 + (523655.0 / (wavelength_nm * wavelength_nm) - 1.5168) / abbe;
}

double sellmeier_index(const Glass& glass, double wavelength_nm)
{
    const double l2 = (wavelength_nm * 1e-3) * (wavelength_nm * 1e-3);
    double n2 = 1;
    for (int i = 0; i < 3; ++i)
        n2 += glass.sellmeier_b[i] * l2 / (l2 - glass.sellmeier_c_um2[i]);
    return n2 >= 0 ? std::sqrt(n2) : NAN;
}

double index_at(double n_d, const Glass& glass, double wavelength_nm)
{
    if (glass.sellmeier)
        return sellmeier_index(glass, wavelength_nm);
    if (glass.abbe != 0)
        return two_term_index(n_d, glass.abbe, wavelength_nm);
    return n_d;
}

std::string check_abbe(double abbe)
{
    if (abbe == 0 || (abbe >= kAbbeMin && abbe <= kAbbeMax))
        return "";
    return "the Abbe number V_d " + format_number(abbe) + " is outside " + format_number(kAbbeMin) + " to " +
           format_number(kAbbeMax) + " (0: no dispersion; optical glasses lie between about 17 and 95)";
}

std::string check_glass(double n_d, const Glass& glass)
{
    if (glass.sellmeier && glass.abbe != 0)
        return "a medium takes an Abbe number or Sellmeier coefficients, not both";
    const std::string abbe = check_abbe(glass.abbe);
    if (!abbe.empty())
        return abbe;
    if (!glass.dispersive())
        return "";
    if (glass.sellmeier) {
        const double lo = kVisibleMinNm * 1e-3 * kVisibleMinNm * 1e-3, hi = kVisibleMaxNm * 1e-3 * kVisibleMaxNm * 1e-3;
        for (int i = 0; i < 3; ++i) {
            if (!std::isfinite(glass.sellmeier_b[i]) || !std::isfinite(glass.sellmeier_c_um2[i]))
                return "the Sellmeier coefficients must be finite";
            const double c = glass.sellmeier_c_um2[i];
            if (c >= lo && c <= hi) {
                std::ostringstream msg;
                msg << "the Sellmeier coefficient C" << i + 1 << " = " << format_number(c)
                    << " µm² is a resonance at " << format_number(std::sqrt(c) * 1e3) << " nm, within the traced "
                    << format_number(kVisibleMinNm) << " to " << format_number(kVisibleMaxNm)
                    << " nm (C is in µm², the square of the resonance's wavelength, as glass catalogues print it; "
                       "it must lie outside "
                    << format_number(lo) << " to " << format_number(hi) << " µm²)";
                return msg.str();
            }
        }
    }
    for (int nm = int(kVisibleMinNm); nm <= int(kVisibleMaxNm); ++nm) {
        const double n = index_at(n_d, glass, nm);
        if (!(n >= 1)) {
            std::ostringstream msg;
            msg << "the index at " << nm << " nm would be " << (std::isnan(n) ? std::string("imaginary") : format_number(n))
                << " (" << (glass.sellmeier ? "Sellmeier formula" : "two-term model from n_d and V_d")
                << "); it must be >= 1 from " << format_number(kVisibleMinNm) << " to " << format_number(kVisibleMaxNm) << " nm";
            return msg.str();
        }
    }
    if (glass.sellmeier) {
        const double at_d = sellmeier_index(glass, kLineDNm);
        if (!(std::fabs(at_d - n_d) <= kSellmeierNdTolerance)) {
            std::ostringstream msg;
            msg << "the Sellmeier coefficients give n_d = " << format_number(at_d) << " at " << format_number(kLineDNm)
                << " nm, but the index written is " << format_number(n_d) << "; they must agree within "
                << format_number(kSellmeierNdTolerance) << " (a render without spectral sampling uses the index written)";
            return msg.str();
        }
    }
    return "";
}

} // namespace plenoptic
