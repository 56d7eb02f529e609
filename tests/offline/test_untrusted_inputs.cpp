// Inputs that once crashed shtool or produced silent garbage, kept as regression tests:
// each must now be refused with a message naming the problem (InputError or an Error
// result), never a crash, an exit 0 with NaN, or a wrapped value.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "scratch_files.h"

#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/sh_inputs.h"
#include "fit/transfer_file.h"
#include "fit/mesh.h"
#include "fit/zh_fit.h"
#include "lighting/image_io.h"
#include "shtool/rotation_helpers.h"
#include "shtool/table.h"
#include "shtool/zhf_rotation.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool {
namespace {

std::string input_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

Table shipped_zhf(int n) {
  const auto t = read_table(find_shipped_table("zhf-shared-N" + std::to_string(n) + ".shtb"));
  EXPECT_TRUE(t.ok());
  return t.value();
}

void set_i32(Table& t, const char* name, std::size_t i, std::int32_t v) {
  for (TableArray& a : t.arrays)
    if (a.name == name) {
      std::vector<std::int32_t> x = a.values<std::int32_t>();
      x[i] = v;
      a = TableArray::from<std::int32_t>(a.name, a.shape, x);
    }
}

TEST(UntrustedZhfLobes, RowStartsBeyondTheNonZerosAreRefused) {
  Table t = shipped_zhf(4);
  ASSERT_TRUE(ZhfLobes::from_table(t).ok());
  set_i32(t, "sparse_row_start", 3, 1 << 30);  // past sparse_col, monotone up to there
  const auto z = ZhfLobes::from_table(t);
  ASSERT_FALSE(z.ok());
  EXPECT_NE(z.error().message.find("sparse_row_start"), std::string::npos) << z.error().message;
}

TEST(UntrustedZhfLobes, HugeBandEntriesAreRefused) {
  Table t = shipped_zhf(4);
  set_i32(t, "bands", 3, std::numeric_limits<std::int32_t>::max());  // 2 * b + 1 overflows
  const auto z = ZhfLobes::from_table(t);
  ASSERT_FALSE(z.ok());
  // Refused where the bands are checked to be 0..n-1, before 2 * b + 1 is formed.
  EXPECT_NE(z.error().message.find("does not hold band 3 at position 3"), std::string::npos) << z.error().message;
}

TEST(UntrustedRotationHelpers, NonFiniteOrHugeValuesAreRefused) {
  const Table good = to_table(compute_rotation_helpers(6), generator_record("test", nlohmann::json::object()));
  ASSERT_TRUE(RotationHelpers::from_table(good).ok());
  for (const char* name : {"x90_val", "dy_sub", "ddy_diag", "ddy_off2"})
    for (double bad : {std::numeric_limits<double>::infinity(), 1e300, std::nan("")}) {
      Table t = good;
      for (TableArray& a : t.arrays)
        if (a.name == name) {
          std::vector<double> x = a.values<double>();
          x[x.size() / 2] = bad;
          a = TableArray::from<double>(a.name, a.shape, x);
        }
      EXPECT_FALSE(RotationHelpers::from_table(t).ok()) << name << " = " << bad;
    }
}

TEST(UntrustedTransfer, HugeOrMistypedValuesAreRefused) {
  int order = 0;
  // Finite but huge: the fit used to index an empty lobe and crash.
  EXPECT_NE(input_error([&] { fit::parse_transfer_json(R"({"order":3,"vectors":[[1,8,1e308,3,8,8,0,3,3]]})", "t", order); })
                .find("beyond 1e100"),
            std::string::npos);
  // 2^32 + 3 used to be read as order 3.
  EXPECT_NE(input_error([&] { fit::parse_transfer_json(R"({"order":4294967299,"vectors":[[1]]})", "t", order); })
                .find("not supported"),
            std::string::npos);
  EXPECT_NE(input_error([&] { fit::parse_transfer_json(R"({"order":-1,"vectors":[[1]]})", "t", order); })
                .find("not supported"),
            std::string::npos);
  // Accepted values give finite fits.
  const std::vector<double> v = fit::parse_transfer_json(R"({"order":2,"vectors":[[1e99,0,1e99,0]]})", "t", order);
  fit::ZhFitOptions o;
  o.order = order;
  o.lobes = 2;
  const fit::ZhFit f = fit::fit_zh(v, o);
  ASSERT_EQ(f.lobes.size(), 2u);
  for (const auto& lobe : f.lobes) ASSERT_EQ(lobe.coeffs.size(), 2u);
}

TEST(UntrustedTransfer, TheMeshRecordIsReadOrRefused) {
  int order = 0;
  fit::TransferMeshRecord record;
  fit::parse_transfer_json(R"({"order":1,"mesh_up":"y","mesh_crc32":4294967295,"normals":"computed","vectors":[[1]]})",
                           "t", order, &record);
  EXPECT_EQ(record.mesh_up, "y");
  EXPECT_EQ(record.mesh_crc32, 4294967295u);
  EXPECT_EQ(record.normals, "computed");
  // The file with `key` set to `value` is refused, the message holding `fragment`.
  auto refused = [&](const std::string& key, const std::string& value, const std::string& fragment) {
    const std::string text = R"({"order":1,"vectors":[[1]],")" + key + "\":" + value + "}";
    EXPECT_NE(input_error([&] { fit::parse_transfer_json(text, "t", order); }).find(fragment), std::string::npos)
        << text;
  };
  for (const char* crc : {"-1", "4294967296", "1.5", "\"x\"", "null"})
    refused("mesh_crc32", crc, "\"mesh_crc32\" must be an unsigned 32-bit integer");
  for (const char* normals : {"3", "\"bogus\""}) refused("normals", normals, "\"normals\" must be");
}

TEST(UntrustedObj, CoordinatesAndIndicesOutOfRange) {
  // A double that is no float, CR-only line endings hiding a NaN, an index beyond int.
  const std::pair<std::string, std::string> cases[] = {
      {"v 1e39 1 1\nv 0 1 0\nv 1 0 0\nf 1 2 3\n", "beyond float range"},
      {"v 0 0 0\rv nan 1 0\rv 1 0 0\rf 1 2 3\r", "line 2: non-finite"},
      {"v 0 0 0\nv 0 1 0\nv 1 0 0\nf 1 2 99999999999\n", "face index 99999999999 is out of range"},
      {"v 0 0 0\r\nv 0 1 0\r\nv 1 0 0\r\nf 1 2 -99999999999\r\n", "out of range"},
  };
  for (const auto& [text, fragment] : cases) {
    const std::string m = input_error([&, text = text] { fit::load_obj_text(text, "m.obj"); });
    EXPECT_NE(m.find(fragment), std::string::npos) << "'" << m << "' lacks '" << fragment << "'";
  }
  // CR-only line endings are otherwise fine.
  EXPECT_EQ(fit::load_obj_text("v 0 0 0\rv 1 0 0\rv 0 1 0\rf 1 2 3\r", "m.obj").triangles.size(), 1u);
}

// The smallest .glb of fuzz_gltf's finding: a buffer of byteLength 0 beside a BIN chunk,
// which tinygltf copied from data.at(0) of an empty vector (std::out_of_range, exit 3).
TEST(UntrustedGltf, BufferOfLengthZeroBesideABinChunk) {
  std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":0}]})";
  json.resize((json.size() + 3) / 4 * 4, ' ');
  std::string glb = "glTF";
  auto u32 = [&](std::size_t v) {
    for (int b = 0; b < 4; ++b) glb.push_back(static_cast<char>((v >> (8 * b)) & 0xff));
  };
  u32(2);
  u32(12 + 8 + json.size() + 8 + 4);
  u32(json.size());
  u32(0x4E4F534A);  // JSON
  glb += json;
  u32(4);
  u32(0x004E4942);  // BIN
  glb += std::string(4, '\0');
  const std::string m = input_error([&] { fit::load_gltf_bytes(glb, "m.glb"); });
  EXPECT_NE(m.find("m.glb: cannot read glTF"), std::string::npos) << "'" << m << "'";
}

// fuzz_images' findings against OpenEXR's C++ reader, which allocated what a header
// claimed before reading it: an attribute's size, a preview's width x height, a
// stringvector's string length (a 364-byte file took 1.8 GB). OpenEXRCore checks every
// claim against the file: refused with its message, nothing allocated.
TEST(UntrustedExr, AttributeClaimsBeyondTheFileAreRefused) {
  const std::string head("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);  // magic, version 2, single part
  const std::string cases[] = {
      head + std::string("huge\0opaque\0\x00\x00\x00\x70", 16) + std::string(64, '\0'),
      head + std::string("thumb\0preview\0\x10\x00\x00\x00\xff\xff\x00\x00\xff\xff\x00\x00", 26) +
          std::string(64, '\0'),
      head + std::string("names\0stringvector\0\x08\x00\x00\x00\x00\x00\x00\x70\x41\x41\x41\x41", 31) +
          std::string(64, '\0'),
  };
  for (const std::string& exr : cases) {
    const std::string m = input_error([&] { lighting::decode_image(exr, "m.exr", std::int64_t(1) << 20); });
    EXPECT_EQ(m.rfind("m.exr: OpenEXR: ", 0), 0u) << "'" << m << "'";
  }
}

// An encoded image whose two windows (data and display, always equal in what shtool
// writes) are rewritten to (0, 0)-(x1, y1).
std::string with_windows(std::string exr, std::int32_t x1, std::int32_t y1) {
  for (const char* attribute : {"dataWindow", "displayWindow"}) {
    const std::string key = std::string(attribute) + std::string("\0box2i\0\x10\x00\x00\x00", 11);
    const std::size_t at = exr.find(key);
    EXPECT_NE(at, std::string::npos) << attribute;
    const std::int32_t box[4] = {0, 0, x1, y1};
    std::memcpy(exr.data() + at + key.size(), box, sizeof box);  // little-endian, as the file
  }
  return exr;
}

// OpenEXR's C++ reader sized its line buffers by the data window on opening (a 364-byte
// file with a 3,997,712-texel-wide window took 36 s under ASan): the window is compared
// with max_texels before any chunk is read.
TEST(UntrustedExr, DataWindowBeyondTheTexelBoundIsRefusedBeforeAnyChunkIsRead) {
  lighting::Image small;
  small.width = 2;
  small.height = 1;
  small.texels.assign(6, 1.0f);
  const std::string exr = with_windows(lighting::encode_exr(small), 3997711, 7);
  const std::string m = input_error([&] { lighting::decode_image(exr, "m.exr", std::int64_t(1) << 20); });
  EXPECT_NE(m.find("m.exr: 3997712 x 8 texels is more than"), std::string::npos) << "'" << m << "'";
}

// Windows the file's chunks do not cover: a wider window than the chunks were encoded
// for, and more rows than there are chunks. Refused, never texels left unwritten.
TEST(UntrustedExr, ChunksThatDoNotMatchTheWindowAreRefused) {
  lighting::Image img;
  img.width = 4;
  img.height = 40;
  img.texels.assign(static_cast<std::size_t>(img.width) * img.height * 3, 0.5f);
  const std::string exr = lighting::encode_exr(img);
  for (const auto& [x1, y1] : {std::pair{3, 79}, std::pair{63, 39}}) {
    const std::string m =
        input_error([&, x1 = x1, y1 = y1] { lighting::decode_image(with_windows(exr, x1, y1), "m.exr", std::int64_t(1) << 20); });
    EXPECT_EQ(m.rfind("m.exr: OpenEXR: ", 0), 0u) << x1 << " x " << y1 << ": '" << m << "'";
  }
}

// A header that claims more chunks than its file could hold (each takes at least 17
// bytes: its table entry, its leader, a byte of data) is refused by its size, before the
// image is allocated: a 313-byte header claiming 16384 x 8192 texels, within the texel
// bound, once cost 1.6 GB before OpenEXR found its chunk table missing.
TEST(UntrustedExr, MoreChunksThanTheFileCanHoldAreRefusedBeforeAllocating) {
  lighting::Image img;
  img.width = 4;
  img.height = 40;
  img.texels.assign(static_cast<std::size_t>(img.width) * img.height * 3, 0.5f);
  const std::string exr = with_windows(lighting::encode_exr(img), 16383, 8191);
  const std::string m = input_error([&] { lighting::decode_image(exr, "m.exr", std::int64_t(1) << 28); });
  EXPECT_NE(m.find("m.exr: OpenEXR: 16384 x 8192 texels in "), std::string::npos) << "'" << m << "'";
  EXPECT_NE(m.find("chunks claimed, more than its " + std::to_string(exr.size()) + " bytes can hold"),
            std::string::npos)
      << "'" << m << "'";
}

TEST(UntrustedExr, AChannelListCutShortIsRefused) {
  // fuzz_images: every declared size fits the file, yet OpenEXR's C++ library allocated
  // 1.6 GB from a size it misread; OpenEXRCore refuses the headers.
  for (const char* file : {"exr_chlist_desync_oom.exr", "exr_missing_attribute_oom.exr"}) {
    const std::string exr =
        test::read_file(std::filesystem::path(SHTOOL_SOURCE_DIR) / "tests/fuzz/corpus/images" / file);
    ASSERT_GT(exr.size(), 200u) << file;
    const std::string m = input_error([&] { lighting::decode_image(exr, "m.exr", std::int64_t(1) << 20); });
    EXPECT_EQ(m.rfind("m.exr: OpenEXR: ", 0), 0u) << file << ": '" << m << "'";
  }
}

TEST(UntrustedPng, AChunkClaimingMoreThanTheFileIsRefusedBeforeStbAllocates) {
  // fuzz_images: an 8 x 4 PNG whose IDAT length field claims 1.7 GB.
  const std::string png = test::read_file(std::filesystem::path(SHTOOL_SOURCE_DIR) /
                                          "tests/fuzz/corpus/images/png_chunk_claims_1_7_gb.png");
  ASSERT_EQ(png.size(), 78u);
  const std::string m = input_error([&] { lighting::decode_image(png, "m.png", std::int64_t(1) << 20); });
  EXPECT_NE(m.find("m.png: PNG: chunk 'IDAT' claims 1785750805 bytes, more than the file holds"), std::string::npos)
      << "'" << m << "'";
}

TEST(UntrustedJsonInputs, DeepNestingAndNonNumbers) {
  const std::string deep = "{\"inputs\": " + std::string(52000, '[') + std::string(52000, ']') + "}";
  EXPECT_NE(input_error([&] { parse_product_inputs(deep, "stdin", 2, 2, 8); }).find("nested more than"),
            std::string::npos);
  EXPECT_NE(input_error([&] { parse_coefficients_json(std::string(52000, '['), "stdin"); }).find("nested more than"),
            std::string::npos);
  // A non-number is named by its type, never dumped (a dump of deep JSON overflowed the stack).
  const std::string m = input_error([&] {
    parse_product_inputs(R"({"inputs": [[1,0,0,0],[0,1,0,[[[1]]]]]})", "stdin", 2, 2, 8);
  });
  EXPECT_NE(m.find("is not a number (array)"), std::string::npos) << m;
}

}  // namespace
}  // namespace shtool
