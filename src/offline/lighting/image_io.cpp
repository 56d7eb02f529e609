#include "lighting/image_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <span>
#include <thread>

#include <stb_image.h>
#include <stb_image_write.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <openexr.h>
#include <ImfThreading.h>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "shtool/table.h"

namespace shtool::lighting {
namespace {

enum class Format { exr, hdr, png, jpeg, unknown };

Format sniff(std::string_view b) {
  auto starts = [&](std::string_view magic) { return b.substr(0, magic.size()) == magic; };
  if (starts(std::string_view("\x76\x2f\x31\x01", 4))) return Format::exr;
  if (starts("#?RADIANCE") || starts("#?RGBE")) return Format::hdr;
  if (starts("\x89PNG\r\n\x1a\n")) return Format::png;
  if (starts("\xff\xd8\xff")) return Format::jpeg;
  return Format::unknown;
}

const char* format_name(Format f) {
  switch (f) {
    case Format::exr: return "OpenEXR";
    case Format::hdr: return "Radiance HDR";
    case Format::png: return "PNG";
    case Format::jpeg: return "JPEG";
    case Format::unknown: break;
  }
  return "unknown";
}

Format format_of_extension(const std::filesystem::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (e == ".exr") return Format::exr;
  if (e == ".hdr" || e == ".rgbe" || e == ".pic") return Format::hdr;
  if (e == ".png") return Format::png;
  if (e == ".jpg" || e == ".jpeg") return Format::jpeg;
  return Format::unknown;
}

[[noreturn]] void fail(const std::filesystem::path& name, const std::string& what) {
  throw InputError(name.string() + ": " + what);
}

void check_size(const std::filesystem::path& name, std::int64_t w, std::int64_t h, std::int64_t max_texels) {
  if (w < 1 || h < 1) fail(name, "the image is empty");
  if (w > max_texels || h > max_texels || w * h > max_texels)
    fail(name, std::to_string(w) + " x " + std::to_string(h) + " texels is more than the " +
                   std::to_string(max_texels) + " accepted");
}

// ---- OpenEXR from and to memory
class MemoryIStream : public Imf::IStream {
 public:
  // With `crc`, the CRC-32 of the bytes is run along as OpenEXR reads them (in order, in
  // its reading thread, while its pool decompresses), so the file's bytes are hashed
  // while they are in cache; finish_crc() hashes what was skipped or read out of order.
  MemoryIStream(std::string_view bytes, const std::string& name, bool crc = false)
      : Imf::IStream(name.c_str()), bytes_(bytes), hashing_(crc) {}
  bool read(char c[], int n) override {
    if (n < 0 || pos_ > bytes_.size() || static_cast<std::uint64_t>(n) > bytes_.size() - pos_)
      throw std::runtime_error("unexpected end of file");
    std::memcpy(c, bytes_.data() + pos_, static_cast<std::size_t>(n));
    if (hashing_ && pos_ == hashed_) {
      crc_ = table_crc32(std::span<const std::byte>(reinterpret_cast<const std::byte*>(c), static_cast<std::size_t>(n)),
                         crc_);
      hashed_ += static_cast<std::uint64_t>(n);
    }
    pos_ += static_cast<std::uint64_t>(n);
    return pos_ < bytes_.size();
  }
  std::uint64_t tellg() override { return pos_; }
  void seekg(std::uint64_t pos) override { pos_ = pos; }
  std::uint32_t finish_crc() {
    const std::string_view rest = bytes_.substr(static_cast<std::size_t>(hashed_));
    hashed_ = bytes_.size();
    return crc_ = table_crc32(
               std::span<const std::byte>(reinterpret_cast<const std::byte*>(rest.data()), rest.size()), crc_);
  }

 private:
  std::string_view bytes_;
  std::uint64_t pos_ = 0;
  bool hashing_ = false;
  std::uint64_t hashed_ = 0;  // bytes [0, hashed_) are in crc_
  std::uint32_t crc_ = 0;
};

class MemoryOStream : public Imf::OStream {
 public:
  MemoryOStream() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    if (pos_ + n > data_.size()) data_.resize(pos_ + n);
    std::memcpy(data_.data() + pos_, c, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
  }
  std::uint64_t tellp() override { return pos_; }
  void seekp(std::uint64_t pos) override { pos_ = static_cast<std::size_t>(pos); }
  std::string& data() { return data_; }

 private:
  std::string data_;
  std::size_t pos_ = 0;
};

// OpenEXR decompresses line blocks on its global pool (exact either way): `threads`
// workers (1: none, the calling thread decodes). The pool is the process's, so its
// size is set under a lock and only when it changes.
int exr_pool(int threads) {
  const int workers = threads <= 0 ? static_cast<int>(std::max(1u, std::thread::hardware_concurrency())) : threads;
  const int pool = workers <= 1 ? 0 : workers;
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  if (Imf::globalThreadCount() != pool) Imf::setGlobalThreadCount(pool);
  return pool;
}

// OpenEXR allocates what a header attribute claims before reading it: a 364-byte file
// whose unknown attribute claims 1.8 GB took that much (fuzz_images), and a preview's
// width x height or a stringvector's string lengths are allocated the same way. This walks
// the headers (name, type, int32 size, value; an empty name ends a header, and an empty
// header ends a multi-part file's list) and refuses a claim the file's bytes cannot hold,
// and a data window beyond max_texels (OpenEXR sizes its line buffers by it on opening).
void check_exr_headers(std::string_view b, const std::filesystem::path& name, std::int64_t max_texels) {
  auto le32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(b[at + k]);
    return v;
  };
  auto too_short = [&] { fail(name, "the OpenEXR header ends before its attributes do"); };
  if (b.size() < 8) too_short();
  const bool multipart = (le32(4) & 0x1000) != 0;
  std::size_t at = 8;
  auto word = [&] {  // a NUL-terminated name
    const std::size_t end = b.find('\0', at);
    if (end == std::string_view::npos) too_short();
    const std::string_view w = b.substr(at, end - at);
    at = end + 1;
    return w;
  };
  for (bool first = true;; first = false) {
    if (at >= b.size()) too_short();
    if (b[at] == '\0' && !first) break;  // the empty header after the last part
    while (true) {
      if (at >= b.size()) too_short();
      if (b[at] == '\0') {
        ++at;
        break;
      }
      const std::string_view attribute = word(), type = word();
      if (b.size() - at < 4) too_short();
      const std::uint32_t size = le32(at);
      at += 4;
      auto claims_too_much = [&] {
        std::string shown;  // the file's bytes, printable ones only
        for (char c : attribute.substr(0, 40)) shown += c >= 0x20 && c < 0x7f ? c : '?';
        fail(name, "OpenEXR attribute '" + shown + "' claims more bytes than the file holds");
      };
      if (size > 0x7fffffffu || size > b.size() - at) claims_too_much();
      const std::string_view value = b.substr(at, size);
      if (type == "preview") {  // width, height, then 4 bytes per pixel
        if (size < 8 || std::uint64_t(le32(at)) * le32(at + 4) > (size - 8) / 4) claims_too_much();
      } else if (type == "stringvector") {  // int32 length, then the string, repeated
        for (std::size_t k = 0; k < value.size();) {
          if (value.size() - k < 4) claims_too_much();
          const std::uint32_t n = le32(at + k);
          if (n > value.size() - k - 4) claims_too_much();
          k += 4 + n;
        }
      }
      if (attribute == "dataWindow" && type == "box2i" && size == 16) {
        const auto corner = [&](int k) { return std::int64_t(static_cast<std::int32_t>(le32(at + 4 * k))); };
        check_size(name, corner(2) - corner(0) + 1, corner(3) - corner(1) + 1, max_texels);
      }
      at += size;
    }
    if (!multipart) break;
  }
}

// OpenEXR's core library (OpenEXRCore, written to be fuzzed) parses the headers with every
// size checked against its neighbours; the C++ library that decodes the pixels trusts
// them: a 405-byte file whose channel list is cut short made it allocate 1.6 GB from a
// size read inside another attribute (fuzz_images). The core parses the headers first
// and its refusal is the message; the pixels are then decoded as before.
thread_local std::string g_exr_core_message;

int64_t exr_core_read(exr_const_context_t, void* user, void* buffer, uint64_t size, uint64_t offset,
                      exr_stream_error_func_ptr_t) {
  const std::string_view& b = *static_cast<const std::string_view*>(user);
  if (offset >= b.size()) return 0;
  const std::size_t n = std::min<std::uint64_t>(size, b.size() - offset);
  std::memcpy(buffer, b.data() + offset, n);
  return static_cast<int64_t>(n);
}

int64_t exr_core_size(exr_const_context_t, void* user) {
  return static_cast<int64_t>(static_cast<const std::string_view*>(user)->size());
}

void exr_core_error(exr_const_context_t, exr_result_t, const char* message) {
  if (g_exr_core_message.empty() && message) g_exr_core_message = message;
}

void check_exr_with_core(std::string_view b, const std::filesystem::path& name) {
  exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
  init.user_data = &b;
  init.read_fn = exr_core_read;
  init.size_fn = exr_core_size;
  init.error_handler_fn = exr_core_error;
  // Strict: every attribute the format requires present and of its type; a header
  // without them is where the C++ library's reader loses its place.
  init.flags = EXR_CONTEXT_FLAG_STRICT_HEADER;
  g_exr_core_message.clear();
  exr_context_t context = nullptr;
  const exr_result_t rc = exr_start_read(&context, name.c_str(), &init);
  if (context) exr_finish(&context);
  if (rc != EXR_ERR_SUCCESS)
    fail(name, "EXR: " + (g_exr_core_message.empty() ? std::string(exr_get_default_error_message(rc))
                                                     : g_exr_core_message));
}

Image decode_exr(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels, int threads,
                 std::uint32_t* crc) {
  check_exr_headers(bytes, name, max_texels);
  check_exr_with_core(bytes, name);
  try {
    MemoryIStream stream(bytes, name.string(), crc != nullptr);
    Imf::InputFile file(stream, exr_pool(threads));
    const Imf::Header& header = file.header();
    const Imath::Box2i data = header.dataWindow(), display = header.displayWindow();
    if (data != display)
      fail(name, "the data window (" + std::to_string(data.min.x) + ", " + std::to_string(data.min.y) + ")-(" +
                     std::to_string(data.max.x) + ", " + std::to_string(data.max.y) +
                     ") differs from the display window (" + std::to_string(display.min.x) + ", " +
                     std::to_string(display.min.y) + ")-(" + std::to_string(display.max.x) + ", " +
                     std::to_string(display.max.y) + "): crop or pad the image to its display window first");
    const std::int64_t w = std::int64_t(data.max.x) - data.min.x + 1, h = std::int64_t(data.max.y) - data.min.y + 1;
    check_size(name, w, h, max_texels);
    const Imf::ChannelList& list = header.channels();
    std::array<const char*, 3> names{"R", "G", "B"};
    const bool rgb = list.findChannel("R") && list.findChannel("G") && list.findChannel("B");
    if (!rgb) {
      if (!list.findChannel("Y")) {
        std::string found;
        for (auto c = list.begin(); c != list.end(); ++c) found += std::string(found.empty() ? "" : ", ") + c.name();
        fail(name, "no R, G, B or Y channels (found: " + (found.empty() ? std::string("none") : found) + ")");
      }
      names = {"Y", "Y", "Y"};
    }
    for (const char* c : names) {
      const Imf::Channel* ch = list.findChannel(c);
      if (ch->xSampling != 1 || ch->ySampling != 1) fail(name, std::string("channel ") + c + " is subsampled");
    }
    Image img;
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    img.texels.assign(static_cast<std::size_t>(w * h * 3), 0.0f);
    Imf::FrameBuffer fb;
    // A frame buffer holds one slice per channel name: grey (Y) goes into red, then is copied.
    for (int c = 0; c < (rgb ? 3 : 1); ++c)
      fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.texels.data() + c, data, 3 * sizeof(float),
                                           static_cast<std::size_t>(w) * 3 * sizeof(float)));
    file.setFrameBuffer(fb);
    file.readPixels(data.min.y, data.max.y);
    if (!rgb)
      for (std::size_t i = 0; i < img.texels.size(); i += 3) img.texels[i + 1] = img.texels[i + 2] = img.texels[i];
    if (crc) *crc = stream.finish_crc();
    return img;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    fail(name, std::string("OpenEXR: ") + e.what());
  }
}

}  // namespace

ChannelImage decode_exr_channels(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels,
                                 const std::vector<std::string>& only) {
  if (sniff(bytes) != Format::exr) fail(name, "not an OpenEXR file");
  check_exr_headers(bytes, name, max_texels);
  check_exr_with_core(bytes, name);
  try {
    MemoryIStream stream(bytes, name.string());
    Imf::InputFile file(stream);
    const Imf::Header& header = file.header();
    const Imath::Box2i data = header.dataWindow();
    if (data != header.displayWindow()) fail(name, "the data window differs from the display window");
    const std::int64_t w = std::int64_t(data.max.x) - data.min.x + 1, h = std::int64_t(data.max.y) - data.min.y + 1;
    check_size(name, w, h, max_texels);
    ChannelImage img;
    img.width = static_cast<int>(w);
    img.height = static_cast<int>(h);
    for (auto c = header.channels().begin(); c != header.channels().end(); ++c) {
      if (c.channel().xSampling != 1 || c.channel().ySampling != 1)
        fail(name, std::string("channel ") + c.name() + " is subsampled");
      if (only.empty()) img.names.push_back(c.name());
    }
    if (!only.empty()) {
      for (const std::string& n : only)
        if (!header.channels().findChannel(n)) fail(name, "no channel '" + n + "'");
      img.names = only;
    }
    const std::size_t k = img.names.size();
    // The texel cap bounds one channel; a header may declare any number of them.
    if (w * h * static_cast<std::int64_t>(k) > (std::int64_t{1} << 30))
      fail(name, std::to_string(k) + " channels of " + std::to_string(w) + " x " + std::to_string(h) +
                     ": more than 2^30 values");
    img.texels.assign(static_cast<std::size_t>(w * h) * k, 0.0f);
    Imf::FrameBuffer fb;
    for (std::size_t c = 0; c < k; ++c)
      fb.insert(img.names[c], Imf::Slice::Make(Imf::FLOAT, img.texels.data() + c, data, k * sizeof(float),
                                               static_cast<std::size_t>(w) * k * sizeof(float)));
    file.setFrameBuffer(fb);
    file.readPixels(data.min.y, data.max.y);
    return img;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    fail(name, std::string("OpenEXR: ") + e.what());
  }
}

namespace {

// stb_image reads zeros past the end of a Radiance file instead of failing, so a
// truncated file (or a header that claims more rows than the data holds) would decode as
// black rows. This walks the scanlines as stb's reader does (new-style run-length
// scanlines for widths 8..32767 that start with 2, 2; otherwise flat RGBE from there on)
// and refuses data that ends early.
void check_hdr_complete(std::string_view b, const std::filesystem::path& name, std::int64_t max_texels) {
  const std::size_t header_end = b.find("\n\n");
  if (header_end == std::string_view::npos) fail(name, "Radiance HDR: no end of header");
  const std::size_t line_end = b.find('\n', header_end + 2);
  if (line_end == std::string_view::npos) fail(name, "Radiance HDR: no resolution line");
  long long h = 0, w = 0;
  char tail = 0;
  const std::string line(b.substr(header_end + 2, line_end - header_end - 2));
  if (std::sscanf(line.c_str(), "-Y %lld +X %lld%c", &h, &w, &tail) != 2)
    fail(name, "Radiance HDR: the resolution line is not '-Y <height> +X <width>'");
  check_size(name, w, h, max_texels);
  std::size_t at = line_end + 1;
  auto need = [&](std::size_t n) {
    if (b.size() - at < n)
      fail(name, "Radiance HDR: the data ends before the " + std::to_string(w) + " x " + std::to_string(h) +
                     " texels of its header");
  };
  for (long long y = 0; y < h; ++y) {
    need(4);
    const auto* p = reinterpret_cast<const unsigned char*>(b.data() + at);
    const bool rle = w >= 8 && w < 32768 && p[0] == 2 && p[1] == 2 && !(p[2] & 0x80);
    if (!rle) {
      // stb then reads the whole image flat from here, starting again at row 0.
      need(static_cast<std::size_t>(4 * w * h));
      return;
    }
    if (((p[2] << 8) | p[3]) != w) fail(name, "Radiance HDR: a scanline's width differs from the header's");
    at += 4;
    for (int component = 0; component < 4; ++component) {
      for (long long x = 0; x < w;) {
        need(1);
        const int count = static_cast<unsigned char>(b[at++]);
        const int run = count > 128 ? count - 128 : count;
        if (run == 0 || x + run > w) fail(name, "Radiance HDR: a run-length scanline is corrupt");
        need(count > 128 ? 1 : static_cast<std::size_t>(count));
        at += count > 128 ? 1 : static_cast<std::size_t>(count);
        x += run;
      }
    }
  }
}

// stb_image fills a truncated JPEG with grey instead of failing: a complete one ends
// with the end-of-image marker. And it returns memory it never wrote for a JPEG without a
// scan: one must come (start-of-scan marker) before the end, found by walking the
// marker segments from the start-of-image.
void check_jpeg_complete(std::string_view b, const std::filesystem::path& name) {
  std::size_t end = b.size();
  while (end > 0 && b[end - 1] == '\0') --end;  // some writers pad
  if (end < 2 || static_cast<unsigned char>(b[end - 2]) != 0xff || static_cast<unsigned char>(b[end - 1]) != 0xd9)
    fail(name, "JPEG: the file ends before its end-of-image marker (truncated)");
  auto byte = [&](std::size_t i) { return static_cast<unsigned char>(b[i]); };
  std::size_t at = 2;  // after SOI
  for (;;) {
    if (at >= end || byte(at) != 0xff) fail(name, "JPEG: a marker segment is malformed before the first scan");
    while (at < end && byte(at) == 0xff) ++at;  // fill bytes
    if (at >= end) fail(name, "JPEG: the file ends before its first scan");
    const unsigned marker = byte(at++);
    if (marker == 0xda) return;  // start of scan
    if (marker == 0xd9) fail(name, "JPEG: no scan (the image holds no pixel data)");
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) continue;  // no length
    if (at + 2 > end) fail(name, "JPEG: the file ends inside a marker segment");
    const std::size_t length = (std::size_t(byte(at)) << 8) | byte(at + 1);
    if (length < 2) fail(name, "JPEG: a marker segment has length below 2");
    at += length;
  }
}

// stb_image allocates what a PNG chunk's length field claims before it reads the chunk:
// a 78-byte file whose IDAT claims 1.7 GB took that much (fuzz_images). Every chunk
// (length, type, data, CRC) must fit the bytes that follow it.
void check_png_chunks(std::string_view b, const std::filesystem::path& name) {
  std::size_t at = 8;  // after the signature
  while (at + 8 <= b.size()) {
    const auto byte = [&](std::size_t i) { return std::uint32_t(static_cast<unsigned char>(b[i])); };
    const std::uint32_t length = byte(at) << 24 | byte(at + 1) << 16 | byte(at + 2) << 8 | byte(at + 3);
    const std::string type(b.substr(at + 4, 4));
    if (length > b.size() - at - 8 || b.size() - at - 8 - length < 4)
      fail(name, "PNG: chunk '" + type + "' claims " + std::to_string(length) + " bytes, more than the file holds");
    at += 12 + std::size_t(length);
    if (type == "IEND") return;
  }
}

// Whether `size` bytes can hold a w x h image at all, checked before a decoder allocates
// for it: a crafted header may claim any size. JPEG codes every 8 x 8 block of the first
// component in at least one bit; PNG's deflate expands at most 1032-fold (258-byte
// matches in a bit or two) the rows of at least one bit per pixel.
void check_bytes_can_hold(std::string_view bytes, Format format, std::int64_t w, std::int64_t h,
                          const std::filesystem::path& name) {
  double least_bytes = 0;
  if (format == Format::jpeg) least_bytes = double(w) * double(h) / 64 / 8;
  if (format == Format::png) least_bytes = double(h) * (1 + std::ceil(double(w) / 8)) / 1032;
  if (double(bytes.size()) + 1024 < least_bytes)
    fail(name, std::string(format_name(format)) + ": " + std::to_string(w) + " x " + std::to_string(h) +
                   " texels cannot be coded in a file of " + std::to_string(bytes.size()) +
                   " bytes (its header is wrong or the file is cut short)");
}

Image decode_stb(std::string_view bytes, const std::filesystem::path& name, Format format, std::int64_t max_texels) {
  if (format == Format::hdr) check_hdr_complete(bytes, name, max_texels);
  if (format == Format::jpeg) check_jpeg_complete(bytes, name);
  if (format == Format::png) check_png_chunks(bytes, name);
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int size = static_cast<int>(std::min<std::size_t>(bytes.size(), INT32_MAX));
  int w = 0, h = 0, comp = 0;
  if (!stbi_info_from_memory(data, size, &w, &h, &comp))
    fail(name, std::string(format_name(format)) + ": " + stbi_failure_reason());
  check_size(name, w, h, max_texels);
  check_bytes_can_hold(bytes, format, w, h, name);
  Image img;
  img.width = w;
  img.height = h;
  img.texels.resize(static_cast<std::size_t>(w) * h * 3);
  auto take = [&](auto* pixels, auto convert) {
    if (!pixels) fail(name, std::string(format_name(format)) + ": " + stbi_failure_reason());
    std::unique_ptr<void, void (*)(void*)> owner(pixels, stbi_image_free);
    for (std::size_t i = 0; i < img.texels.size(); ++i) img.texels[i] = convert(pixels[i]);
  };
  if (format == Format::hdr) {
    take(stbi_loadf_from_memory(data, size, &w, &h, &comp, 3), [](float v) { return v; });
  } else if (stbi_is_16_bit_from_memory(data, size)) {
    take(stbi_load_16_from_memory(data, size, &w, &h, &comp, 3),
         [](stbi_us v) { return static_cast<float>(srgb_to_linear(v / 65535.0)); });
  } else {
    std::array<float, 256> table;
    for (int v = 0; v < 256; ++v) table[v] = static_cast<float>(srgb_to_linear(v / 255.0));
    take(stbi_load_from_memory(data, size, &w, &h, &comp, 3), [&](stbi_uc v) { return table[v]; });
  }
  return img;
}

}  // namespace

double srgb_to_linear(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }
double linear_to_srgb(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055; }

namespace {

// crc: when given, the CRC-32 of the bytes (as input_crc32), hashed during the decode.
Image decode(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels, int threads,
             std::uint32_t* crc) {
  const Format content = sniff(bytes), extension = format_of_extension(name);
  if (content == Format::unknown) {
    if (extension != Format::unknown)
      fail(name, std::string("not a ") + format_name(extension) + " file (its first bytes are not a " +
                     format_name(extension) + " signature)");
    fail(name, "not an image shtool reads (OpenEXR, Radiance .hdr, PNG or JPEG)");
  }
  if (extension != Format::unknown && extension != content)
    fail(name, std::string("the extension says ") + format_name(extension) + " but the content is " +
                   format_name(content));
  if (content == Format::exr) return decode_exr(bytes, name, max_texels, threads, crc);
  Image img = decode_stb(bytes, name, content, max_texels);
  if (crc) *crc = input_crc32(bytes);
  return img;
}

}  // namespace

Image decode_image(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels, int threads) {
  return decode(bytes, name, max_texels, threads, nullptr);
}

ImageFile read_image(const std::filesystem::path& path, std::string_view what, int threads) {
  const MappedInput file(path, what);
  ImageFile f;
  f.image = decode(file.bytes(), path, kMaxImageTexels, threads, &f.crc32);
  return f;
}

std::string encode_exr_channels(const ChannelImage& image, NonFinite non_finite) {
  if (non_finite == NonFinite::refuse) check_finite(std::span<const float>(image.texels), "the image's value");
  Imf::Header header(image.width, image.height);
  header.compression() = Imf::ZIP_COMPRESSION;
  for (const std::string& n : image.names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
  MemoryOStream stream;
  {
    Imf::OutputFile file(stream, header);
    Imf::FrameBuffer fb;
    const std::size_t xs = image.names.size() * sizeof(float), ys = xs * image.width;
    for (std::size_t c = 0; c < image.names.size(); ++c)
      fb.insert(image.names[c], Imf::Slice(Imf::FLOAT, (char*)(image.texels.data() + c), xs, ys));
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  }
  return std::move(stream.data());
}

std::string encode_exr(const Image& image) {
  static constexpr const char* kNames[4] = {"R", "G", "B", "A"};
  ChannelImage named{image.width, image.height, {}, image.texels};
  for (int c = 0; c < image.channels; ++c) named.names.push_back(kNames[c]);
  return encode_exr_channels(named);
}

std::string encode_png(const Image& image, double exposure) {
  check_finite(std::span<const float>(image.texels), "the image's value");
  const double scale = std::exp2(exposure);
  std::vector<unsigned char> bytes(image.texels.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const bool alpha = image.channels == 4 && i % 4 == 3;
    const double v = std::max(0.0, static_cast<double>(image.texels[i]));
    const double mapped = alpha ? std::min(v, 1.0) : linear_to_srgb(v * scale / (1 + v * scale));
    bytes[i] = static_cast<unsigned char>(std::lround(255 * mapped));
  }
  std::string out;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
  };
  if (!stbi_write_png_to_func(append, &out, image.width, image.height, image.channels, bytes.data(),
                              image.width * image.channels))
    throw InputError("PNG encoding failed");
  return out;
}

std::string encode_image_for(const std::filesystem::path& path, const Image& image, std::string_view what,
                             double exposure) {
  switch (format_of_extension(path)) {
    case Format::exr: return encode_exr(image);
    case Format::png: return encode_png(image, exposure);
    default: break;
  }
  throw InputError(std::string(what) + " '" + path.string() + "': write .exr (linear float) or .png (tone-mapped)");
}

}  // namespace shtool::lighting
