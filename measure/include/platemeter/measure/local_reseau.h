#pragma once
// The local reseau correction (docs/measure.md): after the global fit, each
// cross's residual r_k = G_k - F^-1(m_k) (grid mm) is the film deformation
// plus its measuring error at that cross. A point inside a reseau cell gets
// the bilinear interpolation of its four corners' residuals added:
//   g' = F^-1(m) + sum w_k r_k,
// with the weights from the point's fractional cell indices (the grid's
// column/row indices mapped to mm by an affine fit of the master grid). Its
// covariance is J cov_m J^T + sum w_k^2 cov(r_k) (the point's own measurement
// is independent of the crosses'; the fit parameters' errors cancel to first
// order because the same F^-1 enters both terms). Corners without a usable
// residual (missing, rejected) drop out and the weights are renormalized
// (flag local_reseau:partial_cell); points outside the grid take the nearest
// cell's edge values (flag local_reseau:outside_grid).
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "platemeter/grids/definitions.h"
#include "platemeter/measure/corrections.h"

namespace platemeter {

class LocalReseauCorrection {
 public:
  // residuals: cross id -> residual (x, y in mm) with its covariance.
  LocalReseauCorrection(const MasterGrid& grid, std::map<std::string, PlanePoint> residuals);
  // Adds the interpolated residual to a point in grid mm; appends flags.
  PlanePoint Apply(const PlanePoint& grid_point, std::vector<std::string>* flags) const;

 private:
  int columns_ = 0, rows_ = 0;
  double index_from_mm_[6] = {};  // (i, j) = A (x, y) + t: {a00, a01, a10, a11, t0, t1}
  std::map<std::pair<int, int>, PlanePoint> residuals_;  // by (i, j)
};

// "X{i}Y{j}" -> (i, j); false for other ids.
bool ParseReseauId(const std::string& id, int* i, int* j);

}  // namespace platemeter
