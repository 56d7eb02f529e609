#include "interop/spz.h"

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <numbers>
#include <vector>

#include "common/input_error.h"
#include "common/parallel_for.h"

namespace shtool::interop {
namespace {

constexpr std::uint32_t kMagic = 0x5053474e;  // "NGSP" little endian
constexpr float kColorScale = 0.15f;
constexpr int kZstdLevel = 12;  // the reference writer's
constexpr std::uint8_t kFlagAntialiased = 0x1, kFlagExtensions = 0x2;
// Extension record types (spz extensions/README.md): vendor 0xADBE (Adobe), extension 3.
constexpr std::uint32_t kCoordinateSystemRecord = 0xADBE0003;
// The CoordinateSystem values 1..16 of the spz library (splat-types.h), as frame letters.
constexpr std::string_view kCoordinateSystems[17] = {"",    "LDB", "RDB", "LUB", "RUB", "LDF", "RDF", "LUF", "RUF",
                                                     "LFD", "RFD", "LFU", "RFU", "LBD", "RBD", "LBU", "RBU"};
// Largest expansion of the decompressors: deflate's 258-byte match per 2 bits, 1032:1;
// a zstd RLE block (4 bytes) stands for at most 128 KiB.
constexpr double kDeflateRatio = 1032, kZstdRatio = 32768;
constexpr std::size_t kInflateStep = std::size_t(64) << 20;
// The extension records after a gzip file's splats: the known one is 12 bytes; vendor
// records past 16 MiB are refused rather than inflated without end.
constexpr std::size_t kMaxExtensionZone = std::size_t(16) << 20;
// The plausible splats of a v4 file: at most its size x 1024 / 9 (the reference loader's).
constexpr std::uint64_t kMaxCompressionRatio = 1024, kMinBytesPerSplat = 9;

std::uint32_t get_u32(const unsigned char* p) {
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 | std::uint32_t(p[3]) << 24;
}
std::uint64_t get_u64(const unsigned char* p) { return get_u32(p) | std::uint64_t(get_u32(p + 4)) << 32; }
void put_u32(std::string& s, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) s.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
}
void put_u64(std::string& s, std::uint64_t v) {
  put_u32(s, static_cast<std::uint32_t>(v));
  put_u32(s, static_cast<std::uint32_t>(v >> 32));
}
// The header bytes versions 3 and 4 share (magic to flags); its last byte differs:
// reserved in 3, the stream count in 4.
void put_header_start(std::string& s, std::uint32_t version, std::size_t n, int degree, int fractional_bits,
                      std::uint8_t flags) {
  put_u32(s, kMagic);
  put_u32(s, version);
  put_u32(s, static_cast<std::uint32_t>(n));
  s.push_back(static_cast<char>(degree));
  s.push_back(static_cast<char>(fractional_bits));
  s.push_back(static_cast<char>(flags));
}

// The extension records of a file, [u32 type][u32 byteLength][payload] back to back
// until the end of `zone`: the coordinate system's read into header.frame, any other
// type skipped (its payload is vendor data the splats do not depend on; the reference
// loader skips it too, with a warning naming the type).
void read_extension_records(std::string_view zone, const std::string& name, SpzHeader& header) {
  auto fail = [&](const std::string& why) { return InputError(name + ": " + why); };
  const auto* p = reinterpret_cast<const unsigned char*>(zone.data());
  std::size_t at = 0;
  bool seen_frame = false;
  // Unknown types are warned of once each (count and bytes), in the order first seen: a
  // zone of many records must not become as many lines.
  std::vector<std::pair<std::uint32_t, std::pair<std::uint64_t, std::uint64_t>>> skipped;
  while (at < zone.size()) {
    if (zone.size() - at < 8)
      throw fail("truncated extension record: " + std::to_string(zone.size() - at) +
                 " bytes left where a record's 8-byte type and length go");
    const std::uint32_t type = get_u32(p + at), length = get_u32(p + at + 4);
    at += 8;
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%08X", static_cast<unsigned>(type));
    if (length > zone.size() - at)
      throw fail(std::string("truncated extension record of type ") + hex + ": " + std::to_string(length) +
                 " bytes claimed, " + std::to_string(zone.size() - at) + " left");
    if (type == 0) throw fail("an extension record of type 0x00000000, which spz reserves (no extension has it)");
    if (type == kCoordinateSystemRecord) {
      if (length != 4)
        throw fail("an SPZ_ADOBE_coordinate_system record of " + std::to_string(length) + " bytes (4 expected)");
      if (seen_frame) throw fail("two SPZ_ADOBE_coordinate_system records");
      seen_frame = true;
      const std::uint32_t value = get_u32(p + at);
      if (value > 16)
        throw fail("SPZ_ADOBE_coordinate_system names coordinate system " + std::to_string(value) +
                   ": 1..16 are defined (0 unspecified)");
      if (value == 0)
        header.warnings.push_back(name +
                                  ": its SPZ_ADOBE_coordinate_system record says UNSPECIFIED: read in the spz default frame");
      else
        header.frame = std::string(kCoordinateSystems[value]);
    } else {
      auto known = std::find_if(skipped.begin(), skipped.end(), [&](const auto& e) { return e.first == type; });
      if (known == skipped.end()) known = skipped.insert(skipped.end(), {type, {0, 0}});
      ++known->second.first;
      known->second.second += length;
    }
    at += length;
  }
  for (const auto& [type, seen] : skipped) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%08X", static_cast<unsigned>(type));
    header.warnings.push_back(name + ": skipped " +
                              (seen.first == 1 ? std::string("an spz extension record")
                                               : std::to_string(seen.first) + " spz extension records") +
                              " of type " + hex + " (" + std::to_string(seen.second) +
                              " bytes) that shtool does not know");
  }
}

std::size_t sh_dim(int degree) { return static_cast<std::size_t>((degree + 1) * (degree + 1) - 1); }

// Byte sizes of the six attribute blocks: positions, alphas, colours, scales, rotations, SH.
std::array<std::uint64_t, 6> block_sizes(std::uint64_t n, int degree, int version) {
  return {9 * n, n, 3 * n, 3 * n, (version >= 3 ? 4 : 3) * n, 3 * sh_dim(degree) * n};
}

float sigmoid(float x) { return 1.0f / (1.0f + std::exp(-x)); }
std::uint8_t to_u8(float x) { return static_cast<std::uint8_t>(std::clamp(std::round(x), 0.0f, 255.0f)); }

// The byte of an SH coefficient: round(128 x) + 128 to the nearest multiple of the bucket,
// clamped to a byte. 128 x is clamped to [-129, 128] before the conversion to int (past
// that every value gives the end byte anyway), so that a huge coefficient saturates and
// never overflows the int (fmax and fmin also take a NaN to the low end).
std::uint8_t quantise_sh(float x, int bucket) {
  const float scaled = std::fmin(std::fmax(x * 128.0f, -129.0f), 128.0f);
  int q = static_cast<int>(std::round(scaled) + 128.0f);
  q = (q + bucket / 2) / bucket * bucket;
  return static_cast<std::uint8_t>(std::clamp(q, 0, 255));
}
float unquantise_sh(std::uint8_t b) { return (static_cast<float>(b) - 128.0f) / 128.0f; }

// The attributes of every splat from the six blocks (each exactly its size).
constexpr std::size_t kChunk = 4096;

void decode_blocks(const std::array<const unsigned char*, 6>& at, int version, int fractional_bits, SplatScene& s,
                   int threads) {
  const float step = std::ldexp(1.0f, -fractional_bits);
  const std::size_t stride = s.sh_stride(), dim = stride / 3 - 1;
  parallel_for((s.count + kChunk - 1) / kChunk, threads, [&](std::size_t chunk) {
  const std::size_t end = std::min(s.count, (chunk + 1) * kChunk);
  for (std::size_t i = chunk * kChunk; i < end; ++i) {
    for (int c = 0; c < 3; ++c) {
      const unsigned char* p = at[0] + 9 * i + 3 * c;
      std::int32_t v = std::int32_t(p[0]) | std::int32_t(p[1]) << 8 | std::int32_t(p[2]) << 16;
      if (v & 0x800000) v -= 0x1000000;
      s.position[3 * i + c] = static_cast<float>(v) * step;
    }
    // Alpha 0 and 1 have infinite logits: their bytes decode to their bucket's edge.
    const float a = std::clamp(static_cast<float>(at[1][i]), 0.5f, 254.5f) / 255.0f;
    s.opacity[i] = std::log(a / (1.0f - a));
    for (int c = 0; c < 3; ++c) {
      s.sh[i * stride + c] = (static_cast<float>(at[2][3 * i + c]) / 255.0f - 0.5f) / kColorScale;
      s.log_scale[3 * i + c] = static_cast<float>(at[3][3 * i + c]) / 16.0f - 10.0f;
    }
    float q[4];  // x y z w
    if (version >= 3) {
      std::uint32_t comp = get_u32(at[4] + 4 * i);
      const int largest = static_cast<int>(comp >> 30);
      float sum = 0;
      for (int j = 3; j >= 0; --j) {
        if (j == largest) continue;
        const float mag = static_cast<float>(comp & 511u) / 511.0f * std::numbers::sqrt2_v<float> / 2;
        q[j] = (comp & 512u) ? -mag : mag;
        sum += q[j] * q[j];
        comp >>= 10;
      }
      q[largest] = std::sqrt(std::max(0.0f, 1.0f - sum));
    } else {
      float sum = 0;
      for (int c = 0; c < 3; ++c) {
        q[c] = static_cast<float>(at[4][3 * i + c]) / 127.5f - 1.0f;
        sum += q[c] * q[c];
      }
      q[3] = std::sqrt(std::max(0.0f, 1.0f - sum));
    }
    s.rotation[4 * i] = q[3];
    for (int c = 0; c < 3; ++c) s.rotation[4 * i + 1 + c] = q[c];
    const unsigned char* sh = at[5] + 3 * dim * i;
    for (std::size_t k = 0; k < 3 * dim; ++k) s.sh[i * stride + 3 + k] = unquantise_sh(sh[k]);
  }
  });
}

// Inflates up to `want` bytes more into out; returns the zlib status. `out` grows as the
// stream delivers, at most kInflateStep ahead of it: a stream that claims more than it
// holds costs the memory of what it holds, not of what it claims.
int inflate_some(z_stream& zs, std::string& out, std::size_t want) {
  const std::size_t end = out.size() + want;
  std::size_t filled = out.size();
  int status = Z_OK;
  while (filled < end) {
    const std::size_t step = std::min(end - filled, kInflateStep);
    out.resize(filled + step);
    zs.next_out = reinterpret_cast<Bytef*>(out.data() + filled);
    zs.avail_out = static_cast<uInt>(step);
    status = inflate(&zs, Z_NO_FLUSH);
    filled += step - zs.avail_out;
    if (status != Z_OK) break;
    if (zs.avail_out != 0 && zs.avail_in == 0) break;  // the input ended
  }
  out.resize(filled);
  return status;
}

SplatScene read_gzip(std::string_view bytes, const std::string& name, SpzHeader* header, int threads) {
  auto fail = [&](const std::string& why) { return InputError(name + ": " + why); };
  z_stream zs{};
  if (inflateInit2(&zs, 16 + MAX_WBITS) != Z_OK) throw fail("zlib could not start");
  struct End {
    z_stream& z;
    ~End() { inflateEnd(&z); }
  } end{zs};
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  zs.avail_in = static_cast<uInt>(std::min<std::size_t>(bytes.size(), 0xffffffffu));
  if (bytes.size() > 0xffffffffu) throw fail("a gzip spz file past 4 GiB is not read");
  std::string data;
  int status = inflate_some(zs, data, 16);
  if (status != Z_OK && status != Z_STREAM_END) throw fail("not a valid gzip stream (" + std::string(zs.msg ? zs.msg : "zlib error") + ")");
  if (data.size() < 16) throw fail("truncated: the gzip stream ends inside the 16-byte spz header");
  const auto* h = reinterpret_cast<const unsigned char*>(data.data());
  if (get_u32(h) != kMagic) throw fail("the gzip stream does not hold an spz header (no NGSP magic)");
  const std::uint32_t version = get_u32(h + 4), n = get_u32(h + 8);
  const int degree = h[12], fractional_bits = h[13], flags = h[14];
  if (version < 2 || version > 3)
    throw fail("spz version " + std::to_string(version) + " in a gzip stream: versions 2 and 3 are read there");
  if (n == 0) throw fail("no splats (a point count of 0, which spz readers refuse)");
  if (degree > 3) throw fail("SH degree " + std::to_string(degree) + ": degrees 0..3 are read");
  if (fractional_bits > 23) throw fail("fractional bits " + std::to_string(fractional_bits) + " past 23");
  const std::array<std::uint64_t, 6> sizes = block_sizes(n, degree, static_cast<int>(version));
  std::uint64_t total = 0;
  for (std::uint64_t s : sizes) total += s;
  if (static_cast<double>(total) > static_cast<double>(bytes.size()) * kDeflateRatio + 4096)
    throw fail("oversized: " + std::to_string(n) + " splats claimed, more than " + std::to_string(bytes.size()) +
               " compressed bytes can hold");
  data.clear();
  try {
    status = inflate_some(zs, data, total);
  } catch (const std::bad_alloc&) {
    throw fail("out of memory: " + std::to_string(n) + " splats take " + std::to_string(total) + " bytes to decode");
  }
  if (data.size() < total) throw fail("truncated: " + std::to_string(n) + " splats need " + std::to_string(total) +
                                      " bytes after the header, the stream holds " + std::to_string(data.size()));
  if (status != Z_OK && status != Z_STREAM_END) throw fail("corrupt gzip stream (" + std::string(zs.msg ? zs.msg : "zlib error") + ")");
  // After the splats: the extension records when flag 0x2 says so (up to the end of the
  // stream, bounded as the stream is), else nothing.
  std::string more;
  while (status == Z_OK) {
    const std::size_t before = more.size();
    status = inflate_some(zs, more, (flags & kFlagExtensions) ? std::size_t(1) << 16 : 1);
    if (!(flags & kFlagExtensions) && !more.empty()) break;
    if (more.size() > kMaxExtensionZone)
      throw fail("oversized: more than " + std::to_string(kMaxExtensionZone >> 20) +
                 " MiB of extension records after the splats");
    if (status == Z_OK && more.size() == before) break;  // the input ended
  }
  if (!(flags & kFlagExtensions) && !more.empty())
    throw fail("the stream is longer than its " + std::to_string(n) + " splats");
  if (status != Z_STREAM_END) throw fail("truncated: the gzip stream does not end");
  if (zs.avail_in != 0) throw fail("bytes after the end of the gzip stream");
  SpzHeader read{static_cast<int>(version), fractional_bits, (flags & kFlagAntialiased) != 0, {}, {}};
  if (flags & kFlagExtensions) read_extension_records(more, name, read);
  SplatScene s;
  s.resize(n, degree);
  std::array<const unsigned char*, 6> at{};
  const auto* p = reinterpret_cast<const unsigned char*>(data.data());
  for (int k = 0; k < 6; ++k) at[k] = p, p += sizes[k];
  decode_blocks(at, static_cast<int>(version), fractional_bits, s, threads);
  if (header) *header = std::move(read);
  return s;
}

SplatScene read_ngsp(std::string_view bytes, const std::string& name, SpzHeader* header, int threads) {
  auto fail = [&](const std::string& why) { return InputError(name + ": " + why); };
  if (bytes.size() < 32) throw fail("truncated: " + std::to_string(bytes.size()) + " bytes, the spz v4 header needs 32");
  const auto* h = reinterpret_cast<const unsigned char*>(bytes.data());
  const std::uint32_t version = get_u32(h + 4), n = get_u32(h + 8);
  const int degree = h[12], fractional_bits = h[13], flags = h[14], streams = h[15];
  const std::uint32_t toc = get_u32(h + 16);
  if (version != 4) throw fail("spz version " + std::to_string(version) + " with the NGSP header: version 4 is read");
  if (degree > 3) throw fail("SH degree " + std::to_string(degree) + ": degrees 0..3 are read");
  if (fractional_bits > 23) throw fail("fractional bits " + std::to_string(fractional_bits) + " past 23");
  // A point count the file cannot hold is refused before anything is allocated. The
  // bound is the reference loader's (load-spz.cc: kMaxCompressionRatio 1024,
  // kMinBytesPerPoint 9, numPoints <= fileSize x 1024 / 9): the positions alone take 9
  // bytes a splat, and no real stream shrinks more than 1024:1 (zstd's own limit, 32768:1
  // for a run of one byte, would let a 40 KB file claim 20 million splats).
  if (n == 0) throw fail("no splats (a point count of 0, which spz readers refuse)");
  if (std::uint64_t(n) * kMinBytesPerSplat > std::uint64_t(bytes.size()) * kMaxCompressionRatio)
    throw fail("implausible: " + std::to_string(n) + " splats claimed, more than the " + std::to_string(bytes.size()) +
               " bytes of its streams can hold (at most file size x " + std::to_string(kMaxCompressionRatio) + " / " +
               std::to_string(kMinBytesPerSplat) + " = " +
               std::to_string(std::uint64_t(bytes.size()) * kMaxCompressionRatio / kMinBytesPerSplat) + ")");
  const std::array<std::uint64_t, 6> sizes = block_sizes(n, degree, 4);
  // Empty streams are left out: the SH's at degree 0, every one of an empty scene.
  std::vector<int> present;
  for (int k = 0; k < 6; ++k)
    if (sizes[k] > 0) present.push_back(k);
  if (streams != static_cast<int>(present.size()))
    throw fail("inconsistent: " + std::to_string(streams) + " streams for " + std::to_string(n) + " splats of SH degree " +
               std::to_string(degree) + " (" + std::to_string(present.size()) + " expected)");
  if (toc < 32 || toc > bytes.size())
    throw fail("inconsistent: table of contents at byte " + std::to_string(toc) + ", outside the header's end (32) " +
               "and the file's (" + std::to_string(bytes.size()) + ")");
  SpzHeader read{4, fractional_bits, (flags & kFlagAntialiased) != 0, {}, {}};
  if (flags & kFlagExtensions)
    read_extension_records(bytes.substr(32, toc - 32), name, read);
  else if (toc > 32)
    // The reference loader (load-spz.cc) skips them too: only flag 0x2 makes them records.
    read.warnings.push_back(name + ": " + std::to_string(toc - 32) +
                            " bytes between the header and the table of contents, without flag 0x2 (extensions) "
                            "to say what they are: skipped, as the reference loader does");
  const std::uint64_t toc_end = std::uint64_t(toc) + 16ull * streams;
  if (toc_end > bytes.size()) throw fail("truncated: the file ends inside its table of contents");
  std::uint64_t at = toc_end;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> where(streams);  // offset, size
  for (int j = 0; j < streams; ++j) {
    const int k = present[j];
    const std::uint64_t packed = get_u64(h + toc + 16 * j), unpacked = get_u64(h + toc + 16 * j + 8);
    if (unpacked != sizes[k])
      throw fail("inconsistent: stream " + std::to_string(j) + " holds " + std::to_string(unpacked) + " bytes, " +
                 std::to_string(n) + " splats need " + std::to_string(sizes[k]));
    if (packed > bytes.size() - at)
      throw fail("truncated: stream " + std::to_string(j) + " runs past the end of the file");
    if (static_cast<double>(unpacked) > static_cast<double>(packed) * kZstdRatio + 4096)
      throw fail("oversized: stream " + std::to_string(j) + " claims " + std::to_string(unpacked) + " bytes from " +
                 std::to_string(packed));
    const unsigned long long frame = ZSTD_getFrameContentSize(bytes.data() + at, packed);
    if (frame != ZSTD_CONTENTSIZE_UNKNOWN && frame != unpacked)
      throw fail("inconsistent: stream " + std::to_string(j) + "'s zstd frame is not the size its table entry says");
    where[j] = {at, packed};
    at += packed;
  }
  if (at != bytes.size()) throw fail(std::to_string(bytes.size() - at) + " bytes after the last stream");
  // Allocated once the layout holds, and not zero-filled: a stream that fails early has
  // touched (and so cost) only the pages it wrote.
  std::array<std::unique_ptr<unsigned char[]>, 6> blocks;
  try {
    for (int k : present) blocks[k].reset(new unsigned char[sizes[k]]);
  } catch (const std::bad_alloc&) {
    std::uint64_t total = 0;
    for (std::uint64_t size : sizes) total += size;
    throw fail("out of memory: " + std::to_string(n) + " splats take " + std::to_string(total) + " bytes to decode");
  }
  // The streams are independent frames: decompressed side by side, the first problem
  // in stream order reported.
  std::vector<std::string> problems(streams);
  parallel_for(static_cast<std::size_t>(streams), threads, [&](std::size_t j) {
    const int k = present[j];
    const std::size_t got = ZSTD_decompress(blocks[k].get(), sizes[k], bytes.data() + where[j].first, where[j].second);
    if (ZSTD_isError(got))
      problems[j] = "stream " + std::to_string(j) + ": " + ZSTD_getErrorName(got);
    else if (got != sizes[k])
      problems[j] = "truncated: stream " + std::to_string(j) + " decompresses to fewer bytes than its entry says";
  });
  for (const std::string& p : problems)
    if (!p.empty()) throw fail(p);
  SplatScene s;
  s.resize(n, degree);
  std::array<const unsigned char*, 6> ptr{};
  static const unsigned char kNone = 0;  // the empty blocks' (never read)
  for (int k = 0; k < 6; ++k) ptr[k] = blocks[k] ? blocks[k].get() : &kNone;
  decode_blocks(ptr, 4, fractional_bits, s, threads);
  if (header) *header = std::move(read);
  return s;
}

int bucket(int bits) { return 1 << (8 - bits); }

}  // namespace

SplatScene read_spz(std::string_view bytes, const std::string& name, SpzHeader* header, int threads) {
  if (bytes.size() >= 4 && get_u32(reinterpret_cast<const unsigned char*>(bytes.data())) == kMagic)
    return read_ngsp(bytes, name, header, threads);
  if (bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0x1f && static_cast<unsigned char>(bytes[1]) == 0x8b)
    return read_gzip(bytes, name, header, threads);
  throw InputError(name + ": not an spz file (neither the NGSP header of version 4 nor a gzip stream)");
}

bool spz_fixed_point_holds(float coordinate, int fractional_bits) {
  const float q = std::round(std::ldexp(coordinate, fractional_bits));
  return q <= 8388607.0f && q >= -8388608.0f;
}

int spz_fractional_bits(const SplatScene& s) {
  float high = 0, low = 0;
  for (float p : s.position) high = std::max(high, p), low = std::min(low, p);
  // The finest fixed point whose 24 bits (two's complement) reach every position.
  auto fits = [&](int bits) { return spz_fixed_point_holds(high, bits) && spz_fixed_point_holds(low, bits); };
  int fractional_bits = kSpzFractionalBits;
  while (fractional_bits > 0 && !fits(fractional_bits)) --fractional_bits;
  if (!fits(fractional_bits)) {
    std::size_t worst = 0;
    for (std::size_t i = 1; i < s.position.size(); ++i)
      if (std::abs(s.position[i]) > std::abs(s.position[worst])) worst = i;
    throw InputError("splat " + std::to_string(worst / 3) + "'s " + "xyz"[worst % 3] + " = " +
                     message_number(s.position[worst]) +
                     " is past spz's 24-bit fixed point, which holds positions within -8388608..8388607 scene "
                     "units (2^23, with no fractional bit left)");
  }
  return fractional_bits;
}

std::string write_spz(const SplatScene& s, const SpzWriteOptions& o, int threads) {
  if (o.version != 3 && o.version != 4) throw InputError("spz version " + std::to_string(o.version) + ": 3 or 4 is written");
  for (int bits : {o.sh1_bits, o.sh_rest_bits})
    if (bits < 1 || bits > 8) throw InputError("--sh-bits must be in 1..8, got " + std::to_string(bits));
  if (s.count > 0xffffffffu) throw InputError("spz holds at most 2^32 - 1 splats");
  if (s.count == 0) throw InputError("spz cannot hold an empty splat scene (readers refuse a point count of 0)");
  const int fractional_bits = spz_fractional_bits(s);
  const std::size_t n = s.count, stride = s.sh_stride(), dim = sh_dim(s.degree);
  const std::array<std::uint64_t, 6> sizes = block_sizes(n, s.degree, o.version);
  std::array<std::string, 6> blocks;
  for (int k = 0; k < 6; ++k) blocks[k].resize(sizes[k]);
  auto* pos = reinterpret_cast<unsigned char*>(blocks[0].data());
  auto* alpha = reinterpret_cast<unsigned char*>(blocks[1].data());
  auto* colour = reinterpret_cast<unsigned char*>(blocks[2].data());
  auto* scale = reinterpret_cast<unsigned char*>(blocks[3].data());
  auto* rot = reinterpret_cast<unsigned char*>(blocks[4].data());
  auto* sh = reinterpret_cast<unsigned char*>(blocks[5].data());
  const float fixed = std::ldexp(1.0f, fractional_bits);
  const int b1 = bucket(o.sh1_bits), b_rest = bucket(o.sh_rest_bits);
  parallel_for((n + kChunk - 1) / kChunk, threads, [&](std::size_t chunk) {
  const std::size_t end = std::min(n, (chunk + 1) * kChunk);
  for (std::size_t i = chunk * kChunk; i < end; ++i) {
    for (int c = 0; c < 3; ++c) {
      const auto v = static_cast<std::int32_t>(std::round(s.position[3 * i + c] * fixed));
      for (int b = 0; b < 3; ++b) pos[9 * i + 3 * c + b] = static_cast<unsigned char>((v >> (8 * b)) & 0xff);
      colour[3 * i + c] = to_u8(s.sh[i * stride + c] * kColorScale * 255.0f + 0.5f * 255.0f);
      scale[3 * i + c] = to_u8((s.log_scale[3 * i + c] + 10.0f) * 16.0f);
    }
    alpha[i] = to_u8(sigmoid(s.opacity[i]) * 255.0f);
    // Quaternion x y z w, normalised.
    const std::array<float, 4> unit = unit_rotation(&s.rotation[4 * i]);
    const float q[4] = {unit[1], unit[2], unit[3], unit[0]};
    int largest_index = 0;
    for (int j = 1; j < 4; ++j)
      if (std::abs(q[j]) > std::abs(q[largest_index])) largest_index = j;
    const bool negate = q[largest_index] < 0;
    std::uint32_t comp = static_cast<std::uint32_t>(largest_index);
    for (int j = 0; j < 4; ++j) {
      if (j == largest_index) continue;
      const bool sign = (q[j] < 0) != negate;
      const auto mag = static_cast<std::uint32_t>(std::floor(511.0f * std::abs(q[j]) / (std::numbers::sqrt2_v<float> / 2) + 0.5f));
      comp = comp << 10 | static_cast<std::uint32_t>(sign) << 9 | std::min(mag, 511u);
    }
    for (int b = 0; b < 4; ++b) rot[4 * i + b] = static_cast<unsigned char>((comp >> (8 * b)) & 0xff);
    for (std::size_t k = 0; k < 3 * dim; ++k)
      sh[3 * dim * i + k] = quantise_sh(s.sh[i * stride + 3 + k], k < 9 ? b1 : b_rest);
  }
  });
  if (o.coordinate_system > 16)
    throw InputError("spz coordinate system " + std::to_string(o.coordinate_system) + ": 0..16");
  // Extension records: the coordinate system's when the scene is not in spz's default RUB.
  std::string records;
  if (o.coordinate_system != 0) {
    put_u32(records, kCoordinateSystemRecord);
    put_u32(records, 4);  // the payload: one u32
    put_u32(records, o.coordinate_system);
  }
  const std::uint8_t flags = (records.empty() ? 0 : kFlagExtensions) | (o.antialiased ? kFlagAntialiased : 0);
  std::string out;
  if (o.version == 3) {
    std::string plain;
    put_header_start(plain, 3, n, s.degree, fractional_bits, flags);
    plain.push_back(0);  // reserved
    for (const std::string& b : blocks) plain += b;
    plain += records;  // after the SH
    z_stream zs{};
    if (deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) != Z_OK)
      throw InputError("zlib could not start");
    out.resize(deflateBound(&zs, plain.size()));
    zs.next_in = reinterpret_cast<Bytef*>(plain.data());
    zs.next_out = reinterpret_cast<Bytef*>(out.data());
    std::size_t in_left = plain.size(), out_left = out.size();
    int status = Z_OK;
    while (status == Z_OK) {
      zs.avail_in = static_cast<uInt>(std::min<std::size_t>(in_left, 1u << 30));
      zs.avail_out = static_cast<uInt>(std::min<std::size_t>(out_left, 1u << 30));
      const uInt gave = zs.avail_in, room = zs.avail_out;
      status = deflate(&zs, zs.avail_in == in_left ? Z_FINISH : Z_NO_FLUSH);
      in_left -= gave - zs.avail_in;
      out_left -= room - zs.avail_out;
    }
    deflateEnd(&zs);
    if (status != Z_STREAM_END) throw InputError("zlib could not compress the spz stream");
    out.resize(out.size() - out_left);
    return out;
  }
  // Each stream its own frame: compressed side by side.
  std::vector<std::string> packed(6);
  std::vector<std::string> problems(6);
  parallel_for(6, threads, [&](std::size_t k) {
    const std::string& b = blocks[k];
    if (b.empty()) return;
    std::string z(ZSTD_compressBound(b.size()), '\0');
    const std::size_t got = ZSTD_compress(z.data(), z.size(), b.data(), b.size(), kZstdLevel);
    if (ZSTD_isError(got)) problems[k] = std::string("zstd: ") + ZSTD_getErrorName(got);
    z.resize(ZSTD_isError(got) ? 0 : got);
    packed[k] = std::move(z);
  });
  for (const std::string& p : problems)
    if (!p.empty()) throw InputError(p);
  std::erase_if(packed, [](const std::string& z) { return z.empty(); });
  put_header_start(out, 4, n, s.degree, fractional_bits, flags);
  out.push_back(static_cast<char>(packed.size()));
  put_u32(out, static_cast<std::uint32_t>(32 + records.size()));  // the table of contents after the records
  out.append(12, '\0');
  out += records;
  std::size_t j = 0;
  for (int k = 0; k < 6; ++k)
    if (sizes[k] > 0) put_u64(out, packed[j].size()), put_u64(out, sizes[k]), ++j;
  for (const std::string& z : packed) out += z;
  // What readers accept (read_ngsp): a scene that compresses past it (a great many
  // identical splats) is refused rather than written unreadable.
  if (std::uint64_t(n) * kMinBytesPerSplat > std::uint64_t(out.size()) * kMaxCompressionRatio)
    throw InputError("the " + std::to_string(n) + " splats compress to " + std::to_string(out.size()) +
                     " bytes, fewer than spz readers accept for them (file size x " +
                     std::to_string(kMaxCompressionRatio) + " / " + std::to_string(kMinBytesPerSplat) +
                     " splats at most): write --spz-version 3");
  return out;
}

std::string_view spz_coordinate_system_frame(std::uint32_t value) {
  return value >= 1 && value <= 16 ? kCoordinateSystems[value] : std::string_view();
}

std::uint32_t spz_coordinate_system_value(std::string_view letters) {
  std::string up;
  for (char c : letters) up.push_back(static_cast<char>(std::toupper(static_cast<unsigned char>(c))));
  for (std::uint32_t v = 1; v <= 16; ++v)
    if (kCoordinateSystems[v] == up) return v;
  return 0;
}

double spz_sh_error_bound(int degree, const SpzWriteOptions& o) {
  double bound = 0;
  for (int l = 1; l <= degree; ++l) {
    const int b = bucket(l == 1 ? o.sh1_bits : o.sh_rest_bits);
    const double e = (b / 2 + 0.5) / 128.0;
    bound += e * (2 * l + 1) / std::sqrt(4 * std::numbers::pi);
  }
  return bound;
}

// The largest of worst_of_splat(i) over every splat, in chunks of kChunk splats on
// `threads` workers (a maximum: the same on any thread count).
template <class F>
double largest_over_splats(std::size_t count, int threads, F worst_of_splat) {
  std::vector<double> worst_of((count + kChunk - 1) / kChunk, 0.0);
  parallel_for(worst_of.size(), threads, [&](std::size_t chunk) {
    const std::size_t end = std::min(count, (chunk + 1) * kChunk);
    for (std::size_t i = chunk * kChunk; i < end; ++i) worst_of[chunk] = std::max(worst_of[chunk], worst_of_splat(i));
  });
  double worst = 0;
  for (double w : worst_of) worst = std::max(worst, w);
  return worst;
}

double spz_sh_error_of(const SplatScene& s, const SpzWriteOptions& o, int threads) {
  const std::size_t stride = s.sh_stride();
  const int b1 = bucket(o.sh1_bits), b_rest = bucket(o.sh_rest_bits);
  return largest_over_splats(s.count, threads, [&](std::size_t i) {
    double worst = 0;
    for (int c = 0; c < 3; ++c) {
      double sum = 0;
      for (int l = 1; l <= s.degree; ++l) {
        double band = 0;
        for (int k = l * l; k < (l + 1) * (l + 1); ++k) {
          const float x = s.sh[i * stride + 3 * k + c];
          const double d = unquantise_sh(quantise_sh(x, l == 1 ? b1 : b_rest)) - double(x);
          band += d * d;
        }
        sum += std::sqrt(band * (2 * l + 1) / (4 * std::numbers::pi));
      }
      worst = std::max(worst, sum);
    }
    return worst;
  });
}

double spz_dc_error_of(const SplatScene& s, int threads) {
  const std::size_t stride = s.sh_stride();
  const double worst = largest_over_splats(s.count, threads, [&](std::size_t i) {
    double w = 0;
    for (int c = 0; c < 3; ++c) {
      // The colour byte as written and its value as read (clipped past +-0.5 / 0.15).
      const float x = s.sh[i * stride + c];
      const float decoded =
          (static_cast<float>(to_u8(x * kColorScale * 255.0f + 0.5f * 255.0f)) / 255.0f - 0.5f) / kColorScale;
      w = std::max(w, std::abs(double(x) - double(decoded)));
    }
    return w;
  });
  return worst * 0.5 / std::sqrt(std::numbers::pi);
}

double spz_dc_error_bound() { return 0.5 / (kColorScale * 255.0) * 0.5 / std::sqrt(std::numbers::pi); }

}  // namespace shtool::interop
