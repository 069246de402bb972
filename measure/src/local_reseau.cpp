// The local reseau correction (local_reseau.h).
#include "platemeter/measure/local_reseau.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "platemeter/core/error.h"

namespace platemeter {

bool ParseReseauId(const std::string& id, int* i, int* j) {
  int a = 0, b = 0, consumed = 0;
  if (std::sscanf(id.c_str(), "X%dY%d%n", &a, &b, &consumed) != 2 || consumed != static_cast<int>(id.size())) {
    return false;
  }
  *i = a;
  *j = b;
  return true;
}

LocalReseauCorrection::LocalReseauCorrection(const MasterGrid& grid, std::map<std::string, PlanePoint> residuals)
    : columns_(grid.columns), rows_(grid.rows) {
  // Affine (x, y) -> (i, j) over the grid points.
  Eigen::MatrixXd a(grid.points.size(), 3);
  Eigen::MatrixXd b(grid.points.size(), 2);
  int n = 0;
  for (const GridPoint& p : grid.points) {
    int i = 0, j = 0;
    if (!ParseReseauId(p.id, &i, &j)) continue;
    a.row(n) << p.x_mm, p.y_mm, 1.0;
    b.row(n) << i, j;
    ++n;
  }
  if (n < 3 || columns_ < 2 || rows_ < 2) throw Error("grid " + grid.name, "too few reseau points for the local correction");
  const Eigen::MatrixXd x = a.topRows(n).colPivHouseholderQr().solve(b.topRows(n));
  index_from_mm_[0] = x(0, 0); index_from_mm_[1] = x(1, 0);
  index_from_mm_[2] = x(0, 1); index_from_mm_[3] = x(1, 1);
  index_from_mm_[4] = x(2, 0); index_from_mm_[5] = x(2, 1);
  for (auto& [id, r] : residuals) {
    int i = 0, j = 0;
    if (ParseReseauId(id, &i, &j)) residuals_[{i, j}] = r;
  }
}

PlanePoint LocalReseauCorrection::Apply(const PlanePoint& g, std::vector<std::string>* flags) const {
  const double* m = index_from_mm_;
  double u = m[0] * g.x + m[1] * g.y + m[4];
  double v = m[2] * g.x + m[3] * g.y + m[5];
  if (u < 1.0 || u > columns_ || v < 1.0 || v > rows_) {
    flags->push_back("local_reseau:outside_grid");
    u = std::clamp(u, 1.0, static_cast<double>(columns_));
    v = std::clamp(v, 1.0, static_cast<double>(rows_));
  }
  const int i0 = std::min(static_cast<int>(std::floor(u)), columns_ - 1);
  const int j0 = std::min(static_cast<int>(std::floor(v)), rows_ - 1);
  const double fu = u - i0, fv = v - j0;
  const int di[4] = {0, 1, 0, 1}, dj[4] = {0, 0, 1, 1};
  const double w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
  double wsum = 0.0, wmissing = 0.0;
  for (int k = 0; k < 4; ++k) {
    if (residuals_.count({i0 + di[k], j0 + dj[k]})) wsum += w[k];
    else wmissing += w[k];
  }
  if (wsum <= 1e-9) {
    flags->push_back("local_reseau:no_cell");
    return g;
  }
  if (wmissing > 1e-12) flags->push_back("local_reseau:partial_cell");
  PlanePoint out = g;
  for (int k = 0; k < 4; ++k) {
    const auto it = residuals_.find({i0 + di[k], j0 + dj[k]});
    if (it == residuals_.end()) continue;
    const double wk = w[k] / wsum;
    out.x += wk * it->second.x;
    out.y += wk * it->second.y;
    out.cov = out.cov + Covariance2{wk * wk * it->second.cov.xx, wk * wk * it->second.cov.xy, wk * wk * it->second.cov.yy};
  }
  return out;
}

}  // namespace platemeter
