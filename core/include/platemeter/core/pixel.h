#pragma once
// The one pixel convention of platemeter (DESIGN.md):
//   x = column, y = row, and the CENTRE of the top-left pixel is (0, 0).
// So pixel (col, row) covers [col - 0.5, col + 0.5) x [row - 0.5, row + 0.5).
// Other conventions convert at file boundaries only, with the functions below.
// tests/core/pixel_convention_test.cpp pins it with a synthetic dot.

#include <cmath>

namespace platemeter {

struct PixelPoint {
  double x_px = 0.0;  // column
  double y_px = 0.0;  // row
};

// Integer pixel rectangle [x0_px, x0_px + width_px) x [y0_px, y0_px + height_px).
struct PixelRect {
  long x0_px = 0;
  long y0_px = 0;
  long width_px = 0;
  long height_px = 0;
  long x_end_px() const { return x0_px + width_px; }
  long y_end_px() const { return y0_px + height_px; }
  bool empty() const { return width_px <= 0 || height_px <= 0; }
};

// OpenImageIO / OpenCV-resize style continuous coordinates put the top-left
// pixel's corner at 0 (its centre at 0.5).
inline double PixelFromCornerCoordinate(double corner_coordinate) { return corner_coordinate - 0.5; }
inline double CornerCoordinateFromPixel(double pixel) { return pixel + 0.5; }

// FITS (and IRAF, SExtractor output) count from 1 at the centre of the first pixel.
inline double PixelFromFits(double fits_coordinate) { return fits_coordinate - 1.0; }
inline double FitsFromPixel(double pixel) { return pixel + 1.0; }

// The pixel whose area contains a continuous coordinate.
inline long PixelIndexOf(double coordinate_px) { return static_cast<long>(std::floor(coordinate_px + 0.5)); }

}  // namespace platemeter
