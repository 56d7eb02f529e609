// Image files in and out for the lighting jobs: OpenEXR (half or float, any compression
// the library reads), Radiance .hdr (RGBE, run-length or flat) and 8/16-bit PNG and JPEG
// through stb_image, decoded with the exact IEC 61966-2-1 sRGB curve. Images are linear
// float RGB, rows top first. Every file is read through read_input_file and decoded from
// memory, so that the decoders see exactly the bytes that were checked and hashed.
#pragma once

#include "common/finite.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "shtool/env_projection.h"

namespace shtool::lighting {

struct Image {
  int width = 0;
  int height = 0;
  int channels = 3;
  std::vector<float> texels;  // width * height * channels, rows top first

  FloatImageView view() const { return {texels.data(), width, height, channels}; }
};

// Largest image accepted (texels): a bound checked before anything is allocated.
inline constexpr std::int64_t kMaxImageTexels = std::int64_t(1) << 28;

// The format is recognised by the content (magic numbers), not the extension; a file
// whose content does not match its extension (.exr, .hdr, .png, .jpg/.jpeg) is refused
// naming both. Single-channel files become grey RGB; alpha is dropped. An image of more
// than max_texels is refused before anything is allocated. Throws InputError naming `name`.
// OpenEXR decodes its chunks on `threads` threads (0: every core), the others on one.
Image decode_image(std::string_view bytes, const std::filesystem::path& name,
                   std::int64_t max_texels = kMaxImageTexels, int threads = 0);

// The file's bytes (read_input_file, `what` naming the option, read once) decoded, and
// their CRC-32 (input_crc32).
struct ImageFile {
  Image image;
  std::uint32_t crc32 = 0;
};
ImageFile read_image(const std::filesystem::path& path, std::string_view what, int threads = 0);

// Float RGB OpenEXR (ZIP compression); alpha written when the image has 4 channels.
std::string encode_exr(const Image& image);

// An image of named float channels (OpenEXR allows any names), interleaved per texel in
// the order of `names`, rows top first.
struct ChannelImage {
  int width = 0;
  int height = 0;
  std::vector<std::string> names;
  std::vector<float> texels;  // width * height * names.size()
};
// Float OpenEXR, ZIP compression, one channel per name (the file lists them sorted).
// Refuses a NaN or infinite value unless told to keep it (tests crafting bad maps).
std::string encode_exr_channels(const ChannelImage& image, NonFinite non_finite = NonFinite::refuse);
// The channels of an OpenEXR file as float: `only` (in that order; a channel of the file
// not in it is neither read nor stored), or every channel in the file's (sorted) order
// when `only` is empty. Throws InputError naming `name`: not OpenEXR, a channel of `only`
// missing, subsampled channels, a data window other than the display window, more than
// max_texels, more than 2^30 values in all.
ChannelImage decode_exr_channels(std::string_view bytes, const std::filesystem::path& name,
                                 std::int64_t max_texels = kMaxImageTexels,
                                 const std::vector<std::string>& only = {});
// 8-bit PNG of the tone-mapped image: x -> x / (1 + x) per channel (Reinhard) after
// scaling by 2^exposure, then the sRGB transfer curve; alpha (4 channels) kept linear.
std::string encode_png(const Image& image, double exposure = 0);
// By the extension of `path`: .exr or .png (InputError otherwise, naming `what`); the
// exposure applies to PNG only.
std::string encode_image_for(const std::filesystem::path& path, const Image& image, std::string_view what,
                             double exposure = 0);

// The IEC 61966-2-1 curves.
double srgb_to_linear(double v);
double linear_to_srgb(double v);

}  // namespace shtool::lighting
