// The translucent thin-membrane model of [4] (Sec. 4.2 "Parametric models", Eq. 22-23): a
// point's transfer is the circularly symmetric function
//   g(s) = s.z           if s.z >= 0
//        = -alpha s.z    otherwise          (z the surface normal, alpha <= 1 the transparency)
// divided by pi (irradiance to exit radiance), so one ZH lobe along the normal represents
// it exactly, with convolved coefficients
//   g*_l = A_l (1 + (-1)^l alpha) / pi,
// A_l the clamped-cosine kernel (shtool/irradiance.h): a cosine lobe about the normal plus
// alpha times one about the opposite direction. Eq. 23 prints the same numbers: 2/3 (1 - alpha)
// at l = 1, 2 (1 + alpha) (-1)^(l/2-1) / ((l+2)(l-1)) l! / (2^l ((l/2)!)^2) for even l, 0 for odd l > 1.
// Shade with zh_shade_exact or ZhLightTable::shade (shtool/zh_shading.h), the lobe's axis
// being the normal. Nothing here allocates or throws.
#pragma once

#include <span>

namespace shtool {

// g*_l for l < g.size(). Precondition: alpha finite (the model assumes 0 <= alpha <= 1).
void membrane_lobe(double alpha, std::span<double> g) noexcept;

}  // namespace shtool
