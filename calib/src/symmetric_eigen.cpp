// Symmetric eigenproblems and inverses through LAPACK (symmetric_eigen.h).
// The Fortran routines are declared here, as Ceres' own lapack.cc declares
// them. calib links LAPACK::LAPACK (CMake's FindLAPACK); the library is
// already on a machine with Debian's libceres-dev, which depends on it.
#include "symmetric_eigen.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "platemeter/core/error.h"

extern "C" {
void dsytrd_(const char* uplo, const int* n, double* a, const int* lda, double* d, double* e, double* tau,
             double* work, const int* lwork, int* info);
void dsterf_(const int* n, double* d, double* e, int* info);
void dstebz_(const char* range, const char* order, const int* n, const double* vl, const double* vu, const int* il,
             const int* iu, const double* abstol, const double* d, const double* e, int* m, int* nsplit, double* w,
             int* iblock, int* isplit, double* work, int* iwork, int* info);
void dstein_(const int* n, const double* d, const double* e, const int* m, const double* w, const int* iblock,
             const int* isplit, double* z, const int* ldz, double* work, int* iwork, int* ifail, int* info);
void dstedc_(const char* compz, const int* n, double* d, double* e, double* z, const int* ldz, double* work,
             const int* lwork, int* iwork, const int* liwork, int* info);
void dormtr_(const char* side, const char* uplo, const char* trans, const int* m, const int* n, const double* a,
             const int* lda, const double* tau, double* c, const int* ldc, double* work, const int* lwork, int* info);
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info);
void dpotri_(const char* uplo, const int* n, double* a, const int* lda, int* info);
}

namespace platemeter {
namespace {

void Check(int info, const char* routine) {
  if (info != 0) throw Error("adjustment", std::string("LAPACK ") + routine + " failed (info " + std::to_string(info) + ")");
}

}  // namespace

SymmetricEigenproblem::SymmetricEigenproblem(const Eigen::MatrixXd& s) : reflectors_(s) {
  const int n = static_cast<int>(s.rows());
  diagonal_.resize(n);
  off_diagonal_.resize(std::max(1, n - 1));
  tau_.resize(std::max(1, n - 1));
  if (n == 0) return;
  int info = 0, lwork = -1;
  double query = 0.0;
  dsytrd_("L", &n, reflectors_.data(), &n, diagonal_.data(), off_diagonal_.data(), tau_.data(), &query, &lwork, &info);
  Check(info, "dsytrd");
  lwork = std::max(1, static_cast<int>(query));
  std::vector<double> work(lwork);
  dsytrd_("L", &n, reflectors_.data(), &n, diagonal_.data(), off_diagonal_.data(), tau_.data(), work.data(), &lwork,
          &info);
  Check(info, "dsytrd");
}

Eigen::VectorXd SymmetricEigenproblem::Eigenvalues() const {
  const int n = size();
  Eigen::VectorXd values = diagonal_;
  Eigen::VectorXd e = off_diagonal_;  // destroyed
  int info = 0;
  if (n > 0) dsterf_(&n, values.data(), e.data(), &info);
  Check(info, "dsterf");
  return values;
}

bool SymmetricEigenproblem::LowestEigenvectors(int count, Eigen::MatrixXd* vectors) const {
  const int n = size();
  count = std::min(count, n);
  vectors->resize(n, count);
  if (count <= 0) return true;
  // Bisection for the eigenvalues (ordered by split block, as dstein needs), then inverse iteration.
  const char* range = "I";
  const double unused = 0.0, abstol = 2.0 * std::numeric_limits<double>::min();  // most accurate
  const int first = 1;
  int m = 0, nsplit = 0, info = 0;
  std::vector<double> w(n), work(5 * n);
  std::vector<int> iblock(n), isplit(n), iwork(3 * n), ifail(count);
  dstebz_(range, "B", &n, &unused, &unused, &first, &count, &abstol, diagonal_.data(), off_diagonal_.data(), &m,
          &nsplit, w.data(), iblock.data(), isplit.data(), work.data(), iwork.data(), &info);
  if (info != 0 || m != count) return false;
  Eigen::MatrixXd z(n, m);
  dstein_(&n, diagonal_.data(), off_diagonal_.data(), &m, w.data(), iblock.data(), isplit.data(), z.data(), &n,
          work.data(), iwork.data(), ifail.data(), &info);
  if (info != 0) return false;
  BackTransform(&z);
  // Ascending eigenvalue across the split blocks.
  std::vector<int> order(m);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return w[a] < w[b]; });
  for (int k = 0; k < m; ++k) vectors->col(k) = z.col(order[k]);
  return true;
}

void SymmetricEigenproblem::All(Eigen::VectorXd* values, Eigen::MatrixXd* vectors) const {
  const int n = size();
  *values = diagonal_;
  vectors->resize(n, n);
  if (n == 0) return;
  Eigen::VectorXd e = off_diagonal_;  // destroyed
  int info = 0, lwork = -1, liwork = -1, iquery = 0;
  double query = 0.0;
  dstedc_("I", &n, values->data(), e.data(), vectors->data(), &n, &query, &lwork, &iquery, &liwork, &info);
  Check(info, "dstedc");
  lwork = std::max(1, static_cast<int>(query));
  liwork = std::max(1, iquery);
  std::vector<double> work(lwork);
  std::vector<int> iwork(liwork);
  dstedc_("I", &n, values->data(), e.data(), vectors->data(), &n, work.data(), &lwork, iwork.data(), &liwork, &info);
  Check(info, "dstedc");
  BackTransform(vectors);
}

void SymmetricEigenproblem::BackTransform(Eigen::MatrixXd* vectors) const {
  const int n = size(), cols = static_cast<int>(vectors->cols());
  if (n == 0 || cols == 0) return;
  int info = 0, lwork = -1;
  double query = 0.0;
  dormtr_("L", "L", "N", &n, &cols, reflectors_.data(), &n, tau_.data(), vectors->data(), &n, &query, &lwork, &info);
  Check(info, "dormtr");
  lwork = std::max(1, static_cast<int>(query));
  std::vector<double> work(lwork);
  dormtr_("L", "L", "N", &n, &cols, reflectors_.data(), &n, tau_.data(), vectors->data(), &n, work.data(), &lwork,
          &info);
  Check(info, "dormtr");
}

bool InverseOfPositiveDefinite(const Eigen::MatrixXd& s, Eigen::MatrixXd* inverse) {
  const int n = static_cast<int>(s.rows());
  *inverse = s;
  if (n == 0) return true;
  int info = 0;
  dpotrf_("L", &n, inverse->data(), &n, &info);
  if (info != 0) return false;
  dpotri_("L", &n, inverse->data(), &n, &info);
  if (info != 0) return false;
  MirrorLowerTriangle(inverse);  // dpotri leaves the upper triangle as it was
  return true;
}

void MirrorLowerTriangle(Eigen::MatrixXd* m) {
  for (Eigen::Index j = 1; j < m->cols(); ++j) {
    for (Eigen::Index i = 0; i < j; ++i) (*m)(i, j) = (*m)(j, i);
  }
}

}  // namespace platemeter
