// shtool reads OpenEXR with the format's C core (OpenEXRCore), chunk by chunk on every
// worker. The reference is OpenEXR's C++ library reading the same bytes: every
// compression, pixel type and layout it writes must decode to the same floats, bit for
// bit, whatever the thread count.
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <half.h>

#include "lighting/exr_cpp_library.h"
#include "lighting/image_io.h"

namespace shtool::lighting {
namespace {

struct Layout {
  Imf::Compression compression;
  Imf::PixelType type;
  bool tiled;
  int tile = 0;  // tile edge when tiled
};

// A w x h file of channels `names`, random values of `type`, windows offset to (x0, y0).
std::string write_file(const Layout& layout, int w, int h, int x0, int y0, const std::vector<std::string>& names,
                       std::uint32_t seed) {
  const Imath::Box2i window({x0, y0}, {x0 + w - 1, y0 + h - 1});
  Imf::Header header(window, window);
  header.compression() = layout.compression;
  for (const std::string& n : names) header.channels().insert(n, Imf::Channel(layout.type));
  if (layout.tiled) header.setTileDescription(Imf::TileDescription(layout.tile, layout.tile, Imf::ONE_LEVEL));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(-4.0f, 40.0f);
  const std::size_t k = names.size(), n = static_cast<std::size_t>(w) * h * k;
  std::vector<float> f(n);
  std::vector<half> hf(n);
  std::vector<std::uint32_t> u(n);
  for (std::size_t i = 0; i < n; ++i) {
    f[i] = value(rng);
    hf[i] = half(f[i]);
    u[i] = static_cast<std::uint32_t>(rng() >> 8);
  }
  char* base = layout.type == Imf::HALF    ? reinterpret_cast<char*>(hf.data())
               : layout.type == Imf::UINT ? reinterpret_cast<char*>(u.data())
                                          : reinterpret_cast<char*>(f.data());
  const std::size_t size = layout.type == Imf::HALF ? 2 : 4;
  Imf::FrameBuffer fb;
  for (std::size_t c = 0; c < k; ++c)
    fb.insert(names[c], Imf::Slice::Make(layout.type, base + c * size, window, k * size, w * k * size));
  ExrBytesOut out;
  if (layout.tiled) {
    Imf::TiledOutputFile file(out, header);
    file.setFrameBuffer(fb);
    file.writeTiles(0, file.numXTiles() - 1, 0, file.numYTiles() - 1);
  } else {
    Imf::OutputFile file(out, header);
    file.setFrameBuffer(fb);
    file.writePixels(h);
  }
  return out.bytes();
}

// The reference: OpenEXR's C++ library, the channels as float, interleaved.
std::vector<float> read_with_cpp_library(const std::string& bytes, const std::vector<std::string>& names) {
  return decode_exr_with_cpp_library(bytes, names).texels;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(ExrDecode, EqualsOpenExrsCppLibraryForEveryCompressionTypeAndLayout) {
  const std::vector<Layout> layouts = {
      {Imf::NO_COMPRESSION, Imf::FLOAT, false}, {Imf::RLE_COMPRESSION, Imf::HALF, false},
      {Imf::ZIPS_COMPRESSION, Imf::FLOAT, false}, {Imf::ZIP_COMPRESSION, Imf::FLOAT, false},
      {Imf::ZIP_COMPRESSION, Imf::HALF, false},   {Imf::ZIP_COMPRESSION, Imf::UINT, false},
      {Imf::PIZ_COMPRESSION, Imf::HALF, false},   {Imf::PXR24_COMPRESSION, Imf::FLOAT, false},
      {Imf::B44_COMPRESSION, Imf::HALF, false},   {Imf::B44A_COMPRESSION, Imf::HALF, false},
      {Imf::DWAA_COMPRESSION, Imf::HALF, false},  {Imf::DWAB_COMPRESSION, Imf::FLOAT, false},
      {Imf::ZIP_COMPRESSION, Imf::FLOAT, true, 16}, {Imf::PIZ_COMPRESSION, Imf::HALF, true, 7},
      {Imf::NO_COMPRESSION, Imf::UINT, true, 64},
  };
  const std::vector<std::string> rgb = {"R", "G", "B"};
  int index = 0;
  for (const Layout& layout : layouts) {
    SCOPED_TRACE("layout " + std::to_string(index));
    // 37 x 70: neither tiles nor ZIP's 16-line blocks nor PIZ's 32 divide it; windows offset.
    const std::string bytes = write_file(layout, 37, 70, 5, -3, rgb, 100 + index++);
    const std::vector<float> reference = read_with_cpp_library(bytes, rgb);
    for (int threads : {1, 2, 5}) {
      const Image img = decode_image(bytes, "t.exr", kMaxImageTexels, threads);
      ASSERT_EQ(img.width, 37);
      ASSERT_EQ(img.height, 70);
      EXPECT_TRUE(same_bits(img.texels, reference)) << threads << " threads";
    }
    const ChannelImage channels = decode_exr_channels(bytes, "t.exr", kMaxImageTexels, {"B", "R"});
    EXPECT_TRUE(same_bits(channels.texels, read_with_cpp_library(bytes, {"B", "R"})));
  }
}

TEST(ExrDecode, GreyIsReadIntoEveryChannelAndAllChannelsInTheFilesOrder) {
  const std::string grey = write_file({Imf::ZIP_COMPRESSION, Imf::HALF, false}, 9, 20, 0, 0, {"Y"}, 3);
  const std::vector<float> y = read_with_cpp_library(grey, {"Y"});
  const Image img = decode_image(grey, "grey.exr");
  ASSERT_EQ(img.texels.size(), 3 * y.size());
  for (std::size_t t = 0; t < y.size(); ++t)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(img.texels[3 * t + c], y[t]) << t;

  const std::vector<std::string> names = {"Z", "A", "normal.x", "B"};
  const std::string many = write_file({Imf::PIZ_COMPRESSION, Imf::FLOAT, false}, 11, 6, 0, 0, names, 4);
  const ChannelImage all = decode_exr_channels(many, "many.exr");
  const std::vector<std::string> sorted = {"A", "B", "Z", "normal.x"};  // the file lists them sorted
  EXPECT_EQ(all.names, sorted);
  EXPECT_TRUE(same_bits(all.texels, read_with_cpp_library(many, sorted)));
}

TEST(ExrDecode, RefusalsNameTheProblem) {
  const std::string rgb = write_file({Imf::ZIP_COMPRESSION, Imf::FLOAT, false}, 4, 4, 0, 0, {"R", "G", "B"}, 5);
  auto message = [](const auto& f) {
    try {
      f();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([&] { decode_exr_channels(rgb, "c.exr", kMaxImageTexels, {"R", "N"}); }),
            "c.exr: no channel 'N'");
  EXPECT_EQ(message([&] { decode_exr_channels(rgb, "c.exr", kMaxImageTexels, {"G", "G"}); }),
            "c.exr: channel 'G' asked for twice");
  const std::string other = write_file({Imf::ZIP_COMPRESSION, Imf::FLOAT, false}, 4, 4, 0, 0, {"U", "V"}, 6);
  EXPECT_EQ(message([&] { decode_image(other, "uv.exr"); }), "uv.exr: needs channels R, G and B, or Y (found: U, V)");
  EXPECT_EQ(message([&] { decode_image(rgb.substr(0, rgb.size() - 10), "cut.exr"); }).rfind("cut.exr: OpenEXR: ", 0),
            0u);
}

}  // namespace
}  // namespace shtool::lighting
