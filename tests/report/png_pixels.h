#pragma once
// Reading a plot's PNG back (cairo) to check what was drawn, pixel by pixel.
#include <array>
#include <string>

#include <cairo.h>

namespace platemeter::testing {

class PngPixels {
 public:
  explicit PngPixels(const std::string& png_bytes) : bytes_(png_bytes) {
    surface_ = cairo_image_surface_create_from_png_stream(&PngPixels::Read, this);
  }
  ~PngPixels() { cairo_surface_destroy(surface_); }
  PngPixels(const PngPixels&) = delete;
  PngPixels& operator=(const PngPixels&) = delete;

  bool ok() const { return cairo_surface_status(surface_) == CAIRO_STATUS_SUCCESS; }
  int width() const { return cairo_image_surface_get_width(surface_); }
  int height() const { return cairo_image_surface_get_height(surface_); }
  // RGB in 0..255 of pixel (x, y), y down.
  std::array<int, 3> At(int x, int y) const {
    const unsigned char* row = cairo_image_surface_get_data(surface_) + y * cairo_image_surface_get_stride(surface_);
    const unsigned pixel = reinterpret_cast<const unsigned*>(row)[x];
    return {static_cast<int>((pixel >> 16) & 0xff), static_cast<int>((pixel >> 8) & 0xff),
            static_cast<int>(pixel & 0xff)};
  }
  bool IsWhite(int x, int y) const {
    const auto c = At(x, y);
    return c[0] > 245 && c[1] > 245 && c[2] > 245;
  }

 private:
  static cairo_status_t Read(void* closure, unsigned char* data, unsigned int length) {
    auto* self = static_cast<PngPixels*>(closure);
    if (self->offset_ + length > self->bytes_.size()) return CAIRO_STATUS_READ_ERROR;
    self->bytes_.copy(reinterpret_cast<char*>(data), length, self->offset_);
    self->offset_ += length;
    return CAIRO_STATUS_SUCCESS;
  }
  std::string bytes_;
  size_t offset_ = 0;
  cairo_surface_t* surface_ = nullptr;
};

}  // namespace platemeter::testing
