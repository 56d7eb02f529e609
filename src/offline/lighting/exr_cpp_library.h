// OpenEXR's C++ library on bytes in memory. It writes every EXR shtool makes (its own,
// checked images) and decodes the one compression OpenEXRCore 3.1 cannot (DWA); the
// reader is also the reference the core decoder is tested and measured against. Files
// from outside are parsed by OpenEXRCore first (image_io.cpp): this reader trusts headers.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <ImfIO.h>

#include "lighting/image_io.h"

namespace shtool::lighting {

// An Imf output stream that collects the file in a string.
class ExrBytesOut : public Imf::OStream {
 public:
  ExrBytesOut() : Imf::OStream("memory") {}
  void write(const char c[], int n) override;
  std::uint64_t tellp() override { return pos_; }
  void seekp(std::uint64_t pos) override { pos_ = pos; }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
  std::uint64_t pos_ = 0;
};

// The data window's channels `names` (each present) as float, interleaved in that order,
// decoded by the C++ library with its global pool at `threads` workers (0: the calling
// thread). Throws the library's exceptions.
ChannelImage decode_exr_with_cpp_library(std::string_view bytes, const std::vector<std::string>& names,
                                         int threads = 0);

}  // namespace shtool::lighting
