// Niantic's .spz splat files (docs/splats.md restates the format with its source):
// versions 2 and 3 (one gzip stream: a 16-byte header, then the attributes), and 4 (a
// 32-byte header, a table of contents and one zstd frame per attribute). Read: 2, 3, 4;
// written: 3 and 4. Values are quantised as the reference writer does; the SH buckets'
// widths (bits per coefficient) are the writer's choice and are not recorded.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "interop/splat_scene.h"

namespace shtool::interop {

struct SpzWriteOptions {
  int version = 4;       // 3 or 4
  int sh1_bits = 5;      // bits kept of each band-1 SH byte, 1..8
  int sh_rest_bits = 4;  // bands 2 and 3
  // The value of an SPZ_ADOBE_coordinate_system record naming the frame the scene is in
  // (spz_coordinate_system_value); 0 writes no record, the file then being RUB.
  std::uint32_t coordinate_system = 0;
  // Flag 0x1: the splats were trained with antialiasing (Mip-splatting's filter), which a
  // viewer that honours it renders with; carried from an spz input.
  bool antialiased = false;
};

// What a file says about itself beyond the splats.
struct SpzHeader {
  int version = 0;
  int fractional_bits = 0;
  bool antialiased = false;
  // The frame an SPZ_ADOBE_coordinate_system record (type 0xADBE0003) names, as three
  // letters ("RDF"); empty when there is none or it says UNSPECIFIED.
  std::string frame;
  // One line for each extension record skipped (its type and size) and for a
  // coordinate-system record that names no frame.
  std::vector<std::string> warnings;
};

// SPZ_ADOBE_coordinate_system's values 1..16 as frame letters (LDB, RDB, LUB, RUB, LDF,
// RDF, LUF, RUF, LFD, RFD, LFU, RFU, LBD, RBD, LBU, RBU); empty for any other value.
std::string_view spz_coordinate_system_frame(std::uint32_t value);
// The value naming a frame given by letters (any case); 0 when the record names no such
// frame (the 16 have x along R or L).
std::uint32_t spz_coordinate_system_value(std::string_view letters);

// InputError naming `name` on an empty, truncated, oversized or inconsistent file, an unknown
// version, SH degree 4 (not held by SplatScene), a size past what the compressed bytes
// could hold or a malformed extension record. Extension records (flag 0x2; v4 between
// the header and the table of contents, v2/v3 after the SH) are read: the coordinate
// system's into header->frame, any other type skipped with a line in header->warnings.
SplatScene read_spz(std::string_view bytes, const std::string& name, SpzHeader* header = nullptr, int threads = 1);

// InputError when the scene is empty, a position is beyond the 24-bit fixed point at any
// fractional bits, the options are out of range, or (v4) the file would hold more splats
// than readers accept for its size. Positions use 12 fractional bits (the reference
// writer's) or fewer when the scene is larger than 2048 units. No extension record but an
// SPZ_ADOBE_coordinate_system one when options.coordinate_system is not 0 (flag 0x2).
std::string write_spz(const SplatScene& scene, const SpzWriteOptions& options, int threads = 1);

inline constexpr int kSpzFractionalBits = 12;

// Whether a coordinate fits spz's 24-bit two's complement fixed point with these
// fractional bits: round(coordinate 2^bits) within -8388608..8388607.
bool spz_fixed_point_holds(float coordinate, int fractional_bits);

// The fractional bits write_spz stores positions with: kSpzFractionalBits (12, the
// reference writer's: a step of 2^-12 units), or fewer when a coordinate lies beyond
// 2048 units, one bit fewer per doubling; one far splat coarsens every position.
// InputError when a coordinate is past the 24-bit fixed point at 0 bits.
int spz_fractional_bits(const SplatScene& scene);

// The largest change of a splat's colour (one channel, any direction) that the SH
// quantisation of bands 1..D can make, for coefficients within the representable
// [-1, 127/128]: sum_l e_l (2l+1) / sqrt(4 pi), e_l = (floor(b_l/2) + 1/2) / 128,
// b_l = 2^(8 - bits_l) (docs/splats.md).
double spz_sh_error_bound(int degree, const SpzWriteOptions& options);

// The same for the scene's own coefficients, exact per band: max over splats and
// channels of sum_l |delta_l| sqrt((2l+1) / (4 pi)), delta_l the band's quantisation
// error vector (clipping of coefficients beyond [-1, 1] included).
double spz_sh_error_of(const SplatScene& scene, const SpzWriteOptions& options, int threads = 1);

// The largest change of the DC colour: half a step of the colour byte, times y_0^0, for
// coefficients within the byte's range, [-0.5, 0.5] / 0.15 = +-3.33.
double spz_dc_error_bound();
// The same for the scene's own DC coefficients: max over splats and channels of
// |c - decoded| y_0^0, coefficients clipped at +-3.33 included.
double spz_dc_error_of(const SplatScene& scene, int threads = 1);

}  // namespace shtool::interop
