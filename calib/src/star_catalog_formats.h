#pragma once
// Private to the star catalog reader: the two KStars layouts share a selector
// and report into the same list (see star_catalog.h for the layouts).
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "platemeter/calib/star_catalog.h"

namespace platemeter::calib::detail {

// Decides while streaming whether a star is kept (magnitude, then cone).
class StarSelector {
 public:
  explicit StarSelector(const StarQueryOptions& query) : q_(query) {}
  bool KeepMagnitude(double v_mag) const { return v_mag <= q_.faint_limit_mag; }
  bool KeepPosition(double ra_rad, double dec_rad) const {
    return q_.whole_sky ||
           AngularSeparation(ra_rad, dec_rad, q_.center_ra_rad, q_.center_dec_rad) <= q_.radius_rad;
  }

 private:
  StarQueryOptions q_;
};

// `in` is positioned at the start of the file; errors throw Error(path, ...).
void ReadTextStarCatalog(std::ifstream& in, const std::string& path, const StarSelector& select,
                         std::vector<CatalogStar>* out);
void ReadBinaryStarCatalog(std::ifstream& in, const std::string& path, const StarSelector& select,
                           std::vector<CatalogStar>* out);

}  // namespace platemeter::calib::detail
