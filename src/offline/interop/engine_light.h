// SH lighting in each engine's convention (docs/interop.md): export-light and
// import-light. shtool's side is the lighting JSON (lighting/lighting_output.h): radiance
// or irradiance, z-up, Condon-Shortley phase, orthonormal, index l(l+1)+m. Each format
// fixes the engine's frame (a signed permutation from shtool's, overridable), the sign
// convention of its basis, the constants folded into its numbers and their radiometric
// meaning; every engine format holds bands 0..2 only.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/enum_names.h"
#include "lighting/lighting_output.h"
#include "shtool/probe_encoding.h"

namespace shtool::interop {

// l1 and zh3 are a probe's compact encodings (shtool/probe_encoding.h), written by
// export-light only: they keep less than the light, so there is nothing to import.
enum class LightFormat { threejs, filament, filament_radiance, unity, gltf, gltf_khr, babylon, godot, raw, l1, zh3 };
// The formats import-light reads (all but l1 and zh3) and those export-light writes.
const EnumNames<LightFormat>& light_format_names();
const EnumNames<LightFormat>& export_format_names();

// engine = Q w for shtool's w, written as three signed axis names: "x,z,-y" means
// engine x = shtool x, engine y = shtool z, engine z = -shtool y. Q may be a reflection
// (left-handed engines).
struct FrameMap {
  Eigen::Matrix3d q = Eigen::Matrix3d::Identity();
  std::string text = "x,y,z";
};
FrameMap parse_frame_map(std::string_view text);  // InputError on anything but a signed permutation
FrameMap default_frame(LightFormat format);

// The raw format's choices (any order), and the zh3 format's axis.
enum class RawNormalization { orthonormal, four_pi, schmidt };
struct RawOptions {
  bool condon_shortley = true;
  RawNormalization normalization = RawNormalization::orthonormal;
  Zh3Axis zh3_axis = Zh3Axis::luminance;
};
const EnumNames<RawNormalization>& raw_normalization_names();
const EnumNames<Zh3Axis>& zh3_axis_names();

struct ExportedLight {
  std::string text;                // the file's contents
  std::vector<std::string> notes;  // said on stderr (truncation, folded intensity, ...)
};

// `intensity` scales the light: stored in the format's intensity field where it has one
// (three.js LightProbe, EXT_lights_image_based), folded into the numbers otherwise.
ExportedLight export_light(const lighting::Lighting& light, LightFormat format, const FrameMap& frame,
                           double intensity, const RawOptions& raw);

// The inverse: shtool coefficients of the file's light (its intensity applied), in the
// quantity asked for (the formats that hold E/pi give irradiance back, then converted).
// A raw file says its own phase, normalisation and frame. InputError naming `name` on a
// malformed file.
lighting::Lighting import_light(std::string_view text, const std::filesystem::path& name, LightFormat format,
                                const FrameMap& frame, lighting::Quantity quantity);

// three.js's SphericalHarmonics3 of order-3 radiance coefficients in shtool's basis and
// frame (in[3 i + c]): its 27 numbers (coefficient-major, RGB inner) in three's y-up
// frame (x,z,-y) and basis (no Condon-Shortley phase), as LightProbe.sh and
// LightProbeGridWebGL's atlas hold them.
std::array<double, 27> threejs_sh3(const std::array<double, 27>& radiance);

// The engine-frame coefficients in shtool's basis formula applied to engine coordinates:
// g(e) = f(Q^-1 e) (rotation or reflection, any order).
std::vector<double> to_engine_frame(const FrameMap& frame, const std::vector<double>& coefficients);
std::vector<double> from_engine_frame(const FrameMap& frame, const std::vector<double>& coefficients);

}  // namespace shtool::interop
