#include "lighting/exr_cpp_library.h"

#include <cstring>
#include <stdexcept>

#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

namespace shtool::lighting {
namespace {

class ExrBytesIn : public Imf::IStream {
 public:
  explicit ExrBytesIn(std::string_view b) : Imf::IStream("memory"), b_(b) {}
  bool read(char c[], int n) override {
    if (n < 0 || pos_ > b_.size() || std::uint64_t(n) > b_.size() - pos_)
      throw std::runtime_error("unexpected end of file");
    std::memcpy(c, b_.data() + pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::uint64_t>(n);
    return pos_ < b_.size();
  }
  std::uint64_t tellg() override { return pos_; }
  void seekg(std::uint64_t pos) override { pos_ = pos; }

 private:
  std::string_view b_;
  std::uint64_t pos_ = 0;
};

}  // namespace

void ExrBytesOut::write(const char c[], int n) {
  if (pos_ + n > bytes_.size()) bytes_.resize(pos_ + n);
  std::memcpy(bytes_.data() + pos_, c, static_cast<std::size_t>(n));
  pos_ += static_cast<std::uint64_t>(n);
}

ChannelImage decode_exr_with_cpp_library(std::string_view bytes, const std::vector<std::string>& names, int threads) {
  ExrBytesIn stream(bytes);
  Imf::InputFile file(stream, threads);
  const Imath::Box2i window = file.header().dataWindow();
  ChannelImage img;
  img.width = window.max.x - window.min.x + 1;
  img.height = window.max.y - window.min.y + 1;
  img.names = names;
  const std::size_t k = names.size(), pixel = k * sizeof(float), row = std::size_t(img.width) * pixel;
  img.texels.resize(std::size_t(img.width) * std::size_t(img.height) * k);
  Imf::FrameBuffer fb;
  for (std::size_t c = 0; c < k; ++c)
    fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.texels.data() + c, window, pixel, row));
  file.setFrameBuffer(fb);
  file.readPixels(window.min.y, window.max.y);
  return img;
}

}  // namespace shtool::lighting
