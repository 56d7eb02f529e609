#include "lighting/image_io.h"
#include "lighting/exr_cpp_library.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <span>

#include <stb_image.h>
#include <stb_image_write.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <openexr.h>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/parallel_for.h"
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
  const std::string e = lowercase_extension(p);
  if (e == ".exr") return Format::exr;
  if (e == ".hdr" || e == ".rgbe" || e == ".pic") return Format::hdr;
  if (e == ".png") return Format::png;
  if (e == ".jpg" || e == ".jpeg") return Format::jpeg;
  return Format::unknown;
}

void check_size(const std::filesystem::path& name, std::int64_t w, std::int64_t h, std::int64_t max_texels) {
  if (w < 1 || h < 1) fail_input(name, "the image is empty");
  if (w > max_texels || h > max_texels || w * h > max_texels)
    fail_input(name, std::to_string(w) + " x " + std::to_string(h) + " texels is more than the " +
                   std::to_string(max_texels) + " accepted");
}

// ---- OpenEXR
// Files are read by OpenEXR's core library (OpenEXRCore, the format's C core, written to be
// fuzzed): it parses the headers with every size checked against the file and its
// neighbours, strictly (every attribute the format requires present and typed), and
// decodes each chunk into the caller's buffer, converting half and uint to float. The C++
// library trusted what headers claim: a 405-byte file whose channel list was cut short
// made it allocate 1.6 GB from a size read inside another attribute (fuzz_images). Chunks
// are independent, so they are decoded on every worker, each writing its own rows.
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

// The first part of an OpenEXR file, its headers parsed; decode() fills float texels.
class ExrCoreFile {
 public:
  ExrCoreFile(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels)
      : bytes_(bytes), name_(name) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &bytes_;
    init.read_fn = exr_core_read;
    init.size_fn = exr_core_size;
    init.error_handler_fn = exr_core_error;
    init.flags = EXR_CONTEXT_FLAG_STRICT_HEADER;
    g_exr_core_message.clear();
    check(exr_start_read(&context_.handle, name.c_str(), &init));
    exr_storage_t storage;
    check(exr_get_storage(context_.handle, 0, &storage));
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
      fail_input(name, "a deep OpenEXR image (one value per texel is read)");
    tiled_ = storage == EXR_STORAGE_TILED;
    exr_compression_t compression;
    check(exr_get_compression(context_.handle, 0, &compression));
    dwa_ = compression == EXR_COMPRESSION_DWAA || compression == EXR_COMPRESSION_DWAB;
    exr_attr_box2i_t data, display;
    check(exr_get_data_window(context_.handle, 0, &data));
    check(exr_get_display_window(context_.handle, 0, &display));
    auto box = [](const exr_attr_box2i_t& b) {
      char text[96];
      std::snprintf(text, sizeof text, "(%d, %d)-(%d, %d)", b.min.x, b.min.y, b.max.x, b.max.y);
      return std::string(text);
    };
    if (data.min.x != display.min.x || data.min.y != display.min.y || data.max.x != display.max.x ||
        data.max.y != display.max.y)
      fail_input(name, "the data window " + box(data) + " differs from the display window " + box(display) +
                     ": crop or pad the image to its display window first");
    min_y_ = data.min.y;
    const std::int64_t w = std::int64_t(data.max.x) - data.min.x + 1, h = std::int64_t(data.max.y) - data.min.y + 1;
    check_size(name, w, h, max_texels);
    width_ = static_cast<int>(w);
    height_ = static_cast<int>(h);
    const exr_attr_chlist_t* channels = nullptr;
    check(exr_get_channels(context_.handle, 0, &channels));
    for (int c = 0; c < channels->num_channels; ++c) {
      const exr_attr_chlist_entry_t& e = channels->entries[c];
      channels_.emplace_back(e.name.str, static_cast<std::size_t>(e.name.length));
      if (e.x_sampling != 1 || e.y_sampling != 1) fail_input(name, "channel " + channels_.back() + " is subsampled");
    }
    if (tiled_) {  // level (0, 0): the full-resolution image of a mipmapped file
      std::int32_t tile_w = 0, tile_h = 0;
      check(exr_get_tile_sizes(context_.handle, 0, 0, 0, &tile_w, &tile_h));
      if (tile_w < 1 || tile_h < 1) fail_input(name, "OpenEXR: empty tiles");
      tile_w_ = tile_w;
      tile_h_ = tile_h;
      tiles_x_ = static_cast<std::int32_t>((w + tile_w - 1) / tile_w);
      tiles_y_ = static_cast<std::int32_t>((h + tile_h - 1) / tile_h);
      chunks_ = std::size_t(tiles_x_) * std::size_t(tiles_y_);
    } else {
      check(exr_get_scanlines_per_chunk(context_.handle, 0, &lines_per_chunk_));
      if (lines_per_chunk_ < 1) fail_input(name, "OpenEXR: no scanlines per chunk");
      chunks_ = static_cast<std::size_t>((h + lines_per_chunk_ - 1) / lines_per_chunk_);
    }
    // Each chunk of the full-resolution level takes at least its offset-table entry (8
    // bytes), its header (8 bytes for scanlines, 16 for tiles) and a byte of data: a header
    // claiming more than the file can hold is refused here, before the image is allocated
    // (a 313-byte header claiming 16384 x 8192 texels once cost 1.6 GB before OpenEXR
    // found its chunk table missing).
    const std::size_t per_chunk = 8 + (tiled_ ? 16 : 8) + 1;
    if (chunks_ > bytes.size() / per_chunk)
      fail_input(name, "OpenEXR: " + std::to_string(w) + " x " + std::to_string(h) + " texels in " +
                           std::to_string(chunks_) + " chunks claimed, more than its " + std::to_string(bytes.size()) +
                           " bytes can hold (at least " + std::to_string(per_chunk) + " a chunk)");
    // Every chunk's leader read before the image is allocated: a table that points
    // nowhere (a 262 KB file claiming 16384 x 8192 texels took 1.6 GB) fails here.
    for (std::size_t chunk = 0; chunk < chunks_; ++chunk) {
      int x0 = 0, y0 = 0;
      chunk_info(chunk, x0, y0);
    }
  }
  ExrCoreFile(const ExrCoreFile&) = delete;
  ExrCoreFile& operator=(const ExrCoreFile&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<std::string>& channels() const { return channels_; }
  bool has(std::string_view channel) const {
    return std::find(channels_.begin(), channels_.end(), channel) != channels_.end();
  }

  // Channel names[i] into texels[t * stride + i] for every texel t (rows top first), on
  // `threads` workers. Every texel is written: a chunk the file lacks is an error.
  void decode(const std::vector<std::string>& names, float* texels, int stride, int threads) {
    if (dwa_) return decode_dwa(names, texels, stride);
    // A contiguous run of chunks per worker, through one pipeline: its buffers (a ZIP
    // block of a 4096-wide image is 0.8 MB) are allocated once, not per chunk.
    const std::size_t workers = std::min<std::size_t>(std::size_t(std::max(threads, 1)), chunks_);
    parallel_for(workers, static_cast<int>(workers), [&](std::size_t w) {
      exr_decode_pipeline_t pipeline{};  // all zero, as EXR_DECODE_PIPELINE_INITIALIZER
      struct Destroy {
        exr_const_context_t context;
        exr_decode_pipeline_t* pipeline;
        ~Destroy() { exr_decoding_destroy(context, pipeline); }
      } destroy{context_.handle, &pipeline};
      for (std::size_t chunk = chunks_ * w / workers; chunk < chunks_ * (w + 1) / workers; ++chunk)
        decode_chunk(chunk, pipeline, chunk == chunks_ * w / workers, names, texels, stride);
    });
  }

 private:
  void check(exr_result_t rc) const {
    if (rc == EXR_ERR_SUCCESS) return;
    fail_input(name_, "OpenEXR: " + (g_exr_core_message.empty() ? std::string(exr_get_default_error_message(rc))
                                                          : g_exr_core_message));
  }

  // OpenEXRCore 3.1 has no DWA decompressor: those files (headers parsed by the core
  // above) are decoded by the C++ library, on one thread.
  void decode_dwa(const std::vector<std::string>& names, float* texels, int stride) {
    ChannelImage decoded;
    try {
      decoded = decode_exr_with_cpp_library(bytes_, names);
    } catch (const std::exception& e) {
      fail_input(name_, std::string("OpenEXR: ") + e.what());
    }
    const std::size_t k = names.size(), texel_count = std::size_t(width_) * std::size_t(height_);
    if (decoded.texels.size() != texel_count * k) fail_input(name_, "OpenEXR: the DWA decoder's size differs");
    for (std::size_t t = 0; t < texel_count; ++t)
      for (std::size_t c = 0; c < k; ++c) texels[t * std::size_t(stride) + c] = decoded.texels[t * k + c];
  }

  // Chunk `chunk`'s leader (read through the offset table, its sizes checked against the
  // file by the core) and its place (x0, y0) in the image, which must hold it.
  exr_chunk_info_t chunk_info(std::size_t chunk, int& x0, int& y0) const {
    exr_chunk_info_t info;
    x0 = y0 = 0;
    if (tiled_) {
      const int tx = static_cast<int>(chunk % std::size_t(tiles_x_)), ty = static_cast<int>(chunk / std::size_t(tiles_x_));
      check(exr_read_tile_chunk_info(context_.handle, 0, tx, ty, 0, 0, &info));
      x0 = tx * tile_w_;
      y0 = ty * tile_h_;
    } else {
      check(exr_read_scanline_chunk_info(context_.handle, 0, min_y_ + static_cast<int>(chunk) * lines_per_chunk_, &info));
      y0 = info.start_y - min_y_;
    }
    if (x0 < 0 || y0 < 0 || info.width < 0 || info.height < 0 || x0 + info.width > width_ ||
        y0 + info.height > height_)
      fail_input(name_, "OpenEXR: chunk " + std::to_string(chunk) + " lies outside the data window");
    return info;
  }

  void decode_chunk(std::size_t chunk, exr_decode_pipeline_t& decode, bool first, const std::vector<std::string>& names,
                    float* texels, int stride) {
    g_exr_core_message.clear();  // this worker's own
    int x0 = 0, y0 = 0;
    exr_chunk_info_t info = chunk_info(chunk, x0, y0);
    check(first ? exr_decoding_initialize(context_.handle, 0, &info, &decode) : exr_decoding_update(context_.handle, 0, &info, &decode));
    const std::size_t row = std::size_t(width_) * std::size_t(stride);
    for (int c = 0; c < decode.channel_count; ++c) {
      exr_coding_channel_info_t& ch = decode.channels[c];
      const auto slot = std::find(names.begin(), names.end(), std::string_view(ch.channel_name));
      if (slot == names.end()) continue;  // not asked for: skipped by the decoder
      ch.decode_to_ptr = reinterpret_cast<std::uint8_t*>(
          texels + std::size_t(y0) * row + std::size_t(x0) * std::size_t(stride) + std::size_t(slot - names.begin()));
      ch.user_pixel_stride = static_cast<std::int32_t>(std::size_t(stride) * sizeof(float));
      ch.user_line_stride = static_cast<std::int32_t>(row * sizeof(float));
      ch.user_data_type = EXR_PIXEL_FLOAT;
      ch.user_bytes_per_element = sizeof(float);
    }
    check(exr_decoding_choose_default_routines(context_.handle, 0, &decode));
    check(exr_decoding_run(context_.handle, 0, &decode));
  }

  std::string_view bytes_;
  std::filesystem::path name_;
  // Finished however the object ends, also when a refused header throws from the
  // constructor (members are destroyed then; the destructor would not run).
  struct Context {
    exr_context_t handle = nullptr;
    ~Context() {
      if (handle) exr_finish(&handle);
    }
  } context_;
  bool tiled_ = false, dwa_ = false;
  int width_ = 0, height_ = 0, min_y_ = 0;
  std::vector<std::string> channels_;
  std::int32_t lines_per_chunk_ = 0, tiles_x_ = 0, tiles_y_ = 0;
  int tile_w_ = 0, tile_h_ = 0;
  std::size_t chunks_ = 0;
};

Image decode_exr(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels, int threads) {
  ExrCoreFile file(bytes, name, max_texels);
  const bool rgb = file.has("R") && file.has("G") && file.has("B");
  if (!rgb && !file.has("Y")) {
    std::string found;
    for (const std::string& c : file.channels()) found += (found.empty() ? "" : ", ") + c;
    fail_input(name, "needs channels R, G and B, or Y (found: " + (found.empty() ? std::string("none") : found) + ")");
  }
  Image img;
  img.width = file.width();
  img.height = file.height();
  img.texels.resize(std::size_t(img.width) * std::size_t(img.height) * 3);
  // Grey (Y) is decoded into red, then copied.
  file.decode(rgb ? std::vector<std::string>{"R", "G", "B"} : std::vector<std::string>{"Y"}, img.texels.data(), 3,
              resolve_threads(threads));
  if (!rgb)
    for (std::size_t i = 0; i < img.texels.size(); i += 3) img.texels[i + 1] = img.texels[i + 2] = img.texels[i];
  return img;
}


}  // namespace

ChannelImage decode_exr_channels(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels,
                                 const std::vector<std::string>& only) {
  if (sniff(bytes) != Format::exr) fail_input(name, "not an OpenEXR file");
  ExrCoreFile file(bytes, name, max_texels);
  ChannelImage img;
  img.width = file.width();
  img.height = file.height();
  for (std::size_t i = 0; i < only.size(); ++i) {
    if (!file.has(only[i])) fail_input(name, "no channel '" + only[i] + "'");
    if (std::find(only.begin(), only.begin() + i, only[i]) != only.begin() + i)
      fail_input(name, "channel '" + only[i] + "' asked for twice");
  }
  img.names = only.empty() ? file.channels() : only;
  const std::size_t k = img.names.size();
  const std::int64_t w = img.width, h = img.height;
  // The texel cap bounds one channel; a header may declare any number of them.
  if (w * h * static_cast<std::int64_t>(k) > (std::int64_t{1} << 30))
    fail_input(name, std::to_string(k) + " channels of " + std::to_string(w) + " x " + std::to_string(h) +
                   ": more than 2^30 values");
  img.texels.resize(static_cast<std::size_t>(w * h) * k);
  if (k > 0) file.decode(img.names, img.texels.data(), static_cast<int>(k), 1);
  return img;
}

namespace {

// stb_image reads zeros past the end of a Radiance file instead of failing, so a
// truncated file (or a header that claims more rows than the data holds) would decode as
// black rows. This walks the scanlines as stb's reader does (new-style run-length
// scanlines for widths 8..32767 that start with 2, 2; otherwise flat RGBE from there on)
// and refuses data that ends early.
void check_hdr_complete(std::string_view b, const std::filesystem::path& name, std::int64_t max_texels) {
  const std::size_t header_end = b.find("\n\n");
  if (header_end == std::string_view::npos) fail_input(name, "Radiance HDR: no end of header");
  const std::size_t line_end = b.find('\n', header_end + 2);
  if (line_end == std::string_view::npos) fail_input(name, "Radiance HDR: no resolution line");
  long long h = 0, w = 0;
  char tail = 0;
  const std::string line(b.substr(header_end + 2, line_end - header_end - 2));
  if (std::sscanf(line.c_str(), "-Y %lld +X %lld%c", &h, &w, &tail) != 2)
    fail_input(name, "Radiance HDR: the resolution line is not '-Y <height> +X <width>'");
  check_size(name, w, h, max_texels);
  std::size_t at = line_end + 1;
  auto need = [&](std::size_t n) {
    if (b.size() - at < n)
      fail_input(name, "Radiance HDR: the data ends before the " + std::to_string(w) + " x " + std::to_string(h) +
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
    if (((p[2] << 8) | p[3]) != w) fail_input(name, "Radiance HDR: a scanline's width differs from the header's");
    at += 4;
    for (int component = 0; component < 4; ++component) {
      for (long long x = 0; x < w;) {
        need(1);
        const int count = static_cast<unsigned char>(b[at++]);
        const int run = count > 128 ? count - 128 : count;
        if (run == 0 || x + run > w) fail_input(name, "Radiance HDR: a run-length scanline is corrupt");
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
    fail_input(name, "JPEG: the file ends before its end-of-image marker (truncated)");
  auto byte = [&](std::size_t i) { return static_cast<unsigned char>(b[i]); };
  std::size_t at = 2;  // after SOI
  for (;;) {
    if (at >= end || byte(at) != 0xff) fail_input(name, "JPEG: a marker segment is malformed before the first scan");
    while (at < end && byte(at) == 0xff) ++at;  // fill bytes
    if (at >= end) fail_input(name, "JPEG: the file ends before its first scan");
    const unsigned marker = byte(at++);
    if (marker == 0xda) return;  // start of scan
    if (marker == 0xd9) fail_input(name, "JPEG: no scan (the image holds no pixel data)");
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) continue;  // no length
    if (at + 2 > end) fail_input(name, "JPEG: the file ends inside a marker segment");
    const std::size_t length = (std::size_t(byte(at)) << 8) | byte(at + 1);
    if (length < 2) fail_input(name, "JPEG: a marker segment has length below 2");
    at += length;
  }
}

// stb_image allocates what a PNG chunk's length field claims before it reads the chunk:
// a 78-byte file whose IDAT claims 1.7 GB took that much (fuzz_images). Every chunk
// (length, type, data, CRC) must fit the bytes that follow it. The size is read from
// IHDR here: stb_image reports a side past its own limit as "unknown image type".
void check_png_chunks(std::string_view b, const std::filesystem::path& name, std::int64_t max_texels) {
  const auto byte = [&](std::size_t i) { return std::uint32_t(static_cast<unsigned char>(b[i])); };
  const auto be32 = [&](std::size_t i) { return byte(i) << 24 | byte(i + 1) << 16 | byte(i + 2) << 8 | byte(i + 3); };
  if (b.size() < 8 + 8 + 13 || b.substr(12, 4) != "IHDR" || be32(8) != 13)
    fail_input(name, "PNG: the file does not begin with its 13-byte IHDR chunk");
  const std::int64_t w = be32(16), h = be32(20);
  check_size(name, w, h, max_texels);
  // stb_image.h's default STBI_MAX_DIMENSIONS, which the library was built with (the
  // macro lives in its implementation section, out of the header's reach).
  constexpr std::int64_t kStbMaxSide = std::int64_t(1) << 24;
  if (w > kStbMaxSide || h > kStbMaxSide)
    fail_input(name, "PNG: " + std::to_string(w) + " x " + std::to_string(h) + " texels: a side is longer than the " +
                         std::to_string(kStbMaxSide) + " the decoder reads");
  std::size_t at = 8;  // after the signature
  while (at + 8 <= b.size()) {
    const std::uint32_t length = be32(at);
    const std::string type(b.substr(at + 4, 4));
    if (length > b.size() - at - 8 || b.size() - at - 8 - length < 4)
      fail_input(name, "PNG: chunk '" + type + "' claims " + std::to_string(length) + " bytes, more than the file holds");
    at += 12 + std::size_t(length);
    if (type == "IEND") return;
  }
  // stb_image gives no reason for a file that stops between chunks.
  fail_input(name, "PNG: the file ends without its IEND chunk (it is cut short)");
}

// stb_image's reason for its last failure, or a general one where it records none.
std::string stb_reason() {
  const char* reason = stbi_failure_reason();
  return reason && *reason ? reason : "the file is cut short or malformed";
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
    fail_input(name, std::string(format_name(format)) + ": " + std::to_string(w) + " x " + std::to_string(h) +
                   " texels cannot be coded in a file of " + std::to_string(bytes.size()) +
                   " bytes (its header is wrong or the file is cut short)");
}

Image decode_stb(std::string_view bytes, const std::filesystem::path& name, Format format, std::int64_t max_texels) {
  if (format == Format::hdr) check_hdr_complete(bytes, name, max_texels);
  if (format == Format::jpeg) check_jpeg_complete(bytes, name);
  if (format == Format::png) check_png_chunks(bytes, name, max_texels);
  const auto* data = reinterpret_cast<const stbi_uc*>(bytes.data());
  const int size = static_cast<int>(std::min<std::size_t>(bytes.size(), INT32_MAX));
  int w = 0, h = 0, comp = 0;
  if (!stbi_info_from_memory(data, size, &w, &h, &comp))
    fail_input(name, std::string(format_name(format)) + ": " + stb_reason());
  check_size(name, w, h, max_texels);
  check_bytes_can_hold(bytes, format, w, h, name);
  Image img;
  img.width = w;
  img.height = h;
  img.texels.resize(static_cast<std::size_t>(w) * h * 3);
  auto take = [&](auto* pixels, auto convert) {
    if (!pixels) fail_input(name, std::string(format_name(format)) + ": " + stb_reason());
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

// crc: when given, the CRC-32 of the bytes (input_crc32).
Image decode(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels, int threads,
             std::uint32_t* crc) {
  const Format content = sniff(bytes), extension = format_of_extension(name);
  if (content == Format::unknown) {
    if (extension != Format::unknown)
      fail_input(name, std::string("not a ") + format_name(extension) + " file (its first bytes are not a " +
                     format_name(extension) + " signature)");
    fail_input(name, "not an image shtool reads (OpenEXR, Radiance .hdr, PNG or JPEG)");
  }
  if (extension != Format::unknown && extension != content)
    fail_input(name, std::string("the extension says ") + format_name(extension) + " but the content is " +
                   format_name(content));
  Image img = content == Format::exr ? decode_exr(bytes, name, max_texels, threads)
                                     : decode_stb(bytes, name, content, max_texels);
  if (crc) *crc = input_crc32(bytes);
  return img;
}

}  // namespace

Image decode_image(std::string_view bytes, const std::filesystem::path& name, std::int64_t max_texels, int threads) {
  return decode(bytes, name, max_texels, threads, nullptr);
}

namespace {

// check_finite for images: the message names the pixel and channel, not a flat index.
void check_image_finite(std::span<const float> texels, int width, const std::vector<std::string>& names) {
  const std::size_t channels = names.size();
  for (std::size_t i = 0; i < texels.size(); ++i)
    if (!std::isfinite(texels[i])) {
      const std::size_t pixel = i / channels, c = i % channels;
      throw InputError("the image's pixel (" + std::to_string(pixel % static_cast<std::size_t>(width)) + ", " +
                       std::to_string(pixel / static_cast<std::size_t>(width)) + ") " + names[c] +
                       " is not finite (a computation overflowed, under a light too strong for float, say: no "
                       "output holds NaN or infinity)");
    }
}

const std::vector<std::string>& rgba_names() {
  static const std::vector<std::string> names = {"R", "G", "B", "A"};
  return names;
}

}  // namespace

ImageFile read_image(const std::filesystem::path& path, std::string_view what, int threads) {
  const MappedInput file(path, what);
  ImageFile f;
  f.image = decode(file.bytes(), path, kMaxImageTexels, threads, &f.crc32);
  return f;
}

std::string encode_exr_channels(const ChannelImage& image, NonFinite non_finite) {
  if (non_finite == NonFinite::refuse) check_image_finite(image.texels, image.width, image.names);
  Imf::Header header(image.width, image.height);
  header.compression() = Imf::ZIP_COMPRESSION;
  for (const std::string& n : image.names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
  ExrBytesOut stream;
  {
    Imf::OutputFile file(stream, header);
    Imf::FrameBuffer fb;
    const std::size_t xs = image.names.size() * sizeof(float), ys = xs * image.width;
    for (std::size_t c = 0; c < image.names.size(); ++c)
      fb.insert(image.names[c], Imf::Slice(Imf::FLOAT, (char*)(image.texels.data() + c), xs, ys));
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  }
  return std::move(stream.bytes());
}

std::string encode_exr(const Image& image) {
  static constexpr const char* kNames[4] = {"R", "G", "B", "A"};
  ChannelImage named{image.width, image.height, {}, image.texels};
  for (int c = 0; c < image.channels; ++c) named.names.push_back(kNames[c]);
  return encode_exr_channels(named);
}

std::string encode_png(const Image& image, double exposure) {
  check_image_finite(image.texels, image.width, {rgba_names().begin(), rgba_names().begin() + image.channels});
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
