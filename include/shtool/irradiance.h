// Radiance and irradiance coefficients (docs/lighting.md, docs/conventions.md).
//
// "radiance" coefficients are those of L(w) itself; "irradiance" coefficients are those
// of E(n) = integral L(w) max(n . w, 0) dw, E_lm = A_l L_lm with the clamped-cosine
// kernel ([13] Sec. 3): A_0 = pi, A_1 = 2 pi / 3, A_l = 0 for odd l > 1 and, for even l,
// A_l = 2 pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) * l! / (2^l ((l/2)!)^2). No 1/pi is folded in.
#pragma once

#include <span>

namespace shtool {

// A_l of the clamped-cosine kernel, any l >= 0.
double clamped_cosine_band(int l);

// Multiplies every coefficient of band l by factors[l]: coefficients[i * channels + c],
// N^2 = coefficients.size() / channels, factors.size() >= N.
void scale_bands(std::span<const double> factors, int channels, std::span<double> coefficients);

// Radiance coefficients to irradiance coefficients in place (scale_bands by A_l).
void radiance_to_irradiance(int channels, std::span<double> coefficients);

}  // namespace shtool
