// KStars binary starData file (layout documented in star_catalog.h).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <numbers>

#include <fmt/format.h>

#include "platemeter/core/error.h"
#include "star_catalog_formats.h"

namespace platemeter::calib::detail {
namespace {

constexpr int kDescriptionBytes = 124;
constexpr int kRecordBytes = 32;

struct FieldDescriptor {
  std::string name;
  int size = 0;
  int32_t scale = 0;
};

// The 11 fields of the 32-byte starData record, in order, with their sizes.
constexpr std::array<std::pair<const char*, int>, 11> kExpectedFields{{{"RA", 4},
                                                                        {"Dec", 4},
                                                                        {"dRA", 4},
                                                                        {"dDec", 4},
                                                                        {"parallax", 4},
                                                                        {"HD", 4},
                                                                        {"mag", 2},
                                                                        {"bv_index", 2},
                                                                        {"spec_type", 2},
                                                                        {"flags", 1},
                                                                        {"unused", 1}}};

// Positions in the Debian kstars-data 3.6 binary files are at the Hipparcos
// epoch J1991.25, not J2000: Sirius, Arcturus and Vega sit exactly 8.75 yr of
// proper motion from their J2000 places. They are moved to J2000 here.
constexpr double kBinaryEpochJyear = 1991.25;
constexpr double kMasToRad = std::numbers::pi / (180.0 * 3600.0 * 1000.0);

// Linear motion on the sphere (tangent-plane step, renormalised): over 8.75 yr
// the neglected perspective terms stay below 1 mas for all but a handful of stars.
void MoveToJ2000(CatalogStar* s) {
  const double years = 2000.0 - kBinaryEpochJyear;
  const double ca = std::cos(s->ra_rad), sa = std::sin(s->ra_rad);
  const double cd = std::cos(s->dec_rad), sd = std::sin(s->dec_rad);
  const double mu_e = s->pm_ra_mas_yr * kMasToRad * years, mu_n = s->pm_dec_mas_yr * kMasToRad * years;
  const double x = cd * ca - mu_e * sa - mu_n * sd * ca;
  const double y = cd * sa + mu_e * ca - mu_n * sd * sa;
  const double z = sd + mu_n * cd;
  s->ra_rad = std::atan2(y, x);
  if (s->ra_rad < 0.0) s->ra_rad += 2.0 * std::numbers::pi;
  s->dec_rad = std::atan2(z, std::hypot(x, y));
}

class Reader {
 public:
  Reader(std::ifstream& in, const std::string& path, bool swap) : in_(in), path_(path), swap_(swap) {}

  void Bytes(void* dst, size_t n, const char* what) {
    in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n));
    if (static_cast<size_t>(in_.gcount()) != n)
      throw Error(path_, fmt::format("truncated binary star catalog while reading {}", what));
  }
  template <typename T>
  T Value(const char* what) {
    T v;
    Bytes(&v, sizeof v, what);
    return Fix(v);
  }
  template <typename T>
  T Fix(T v) const {
    if (!swap_) return v;
    unsigned char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    std::reverse(b, b + sizeof v);
    std::memcpy(&v, b, sizeof v);
    return v;
  }
  template <typename T>
  T At(const unsigned char* p) const {
    T v;
    std::memcpy(&v, p, sizeof v);
    return Fix(v);
  }

 private:
  std::ifstream& in_;
  const std::string& path_;
  bool swap_;
};

}  // namespace

void ReadBinaryStarCatalog(std::ifstream& in, const std::string& path, const StarSelector& select,
                           std::vector<CatalogStar>* out) {
  in.seekg(0, std::ios::end);
  const uint64_t file_size = static_cast<uint64_t>(in.tellg());
  in.seekg(kDescriptionBytes);
  char marker[2];
  in.read(marker, 2);
  // 0x4B53 stored little-endian reads as 'S','K'; swap on a big-endian file.
  const bool file_little = marker[0] == 'S';
  const bool host_little = std::endian::native == std::endian::little;
  Reader r(in, path, file_little != host_little);

  const int version = r.Value<uint8_t>("the format version");
  if (version != 1) throw Error(path, fmt::format("binary star catalog version {} (only version 1 is known)", version));
  const int nfields = r.Value<uint16_t>("the field count");
  if (nfields != static_cast<int>(kExpectedFields.size()))
    throw Error(path, fmt::format("{} field descriptors; a 32-byte starData record has 11 (deep-star "
                                  "16-byte files are not supported)", nfields));
  std::vector<FieldDescriptor> fields(nfields);
  for (int i = 0; i < nfields; ++i) {
    char name[11] = {};
    r.Bytes(name, 10, "a field descriptor");
    fields[i].name = name;
    fields[i].size = r.Value<uint8_t>("a field descriptor");
    r.Value<uint8_t>("a field descriptor");  // type code, implied by the name
    fields[i].scale = r.Value<int32_t>("a field descriptor");
    if (fields[i].name != kExpectedFields[i].first || fields[i].size != kExpectedFields[i].second)
      throw Error(path, fmt::format("field {} is '{}' of {} bytes; expected '{}' of {} bytes", i + 1,
                                    fields[i].name, fields[i].size, kExpectedFields[i].first,
                                    kExpectedFields[i].second));
  }
  auto scale = [&](int i) {
    if (fields[i].scale <= 0)
      throw Error(path, fmt::format("field '{}' has scale {}", fields[i].name, fields[i].scale));
    return static_cast<double>(fields[i].scale);
  };
  const double ra_scale = scale(0), dec_scale = scale(1), pmra_scale = scale(2), pmdec_scale = scale(3),
               plx_scale = scale(4), mag_scale = scale(6), bv_scale = scale(7);

  const uint32_t ntrixels = r.Value<uint32_t>("the trixel count");
  if (ntrixels == 0 || ntrixels > (1u << 24) || uint64_t(ntrixels) * 12 > file_size)
    throw Error(path, fmt::format("implausible trixel count {}", ntrixels));
  struct Trixel {
    uint32_t id, offset, count;
  };
  std::vector<Trixel> index(ntrixels);
  for (auto& t : index) {
    t.id = r.Value<uint32_t>("the trixel index");
    t.offset = r.Value<uint32_t>("the trixel index");
    t.count = r.Value<uint32_t>("the trixel index");
    if (uint64_t(t.offset) + uint64_t(t.count) * kRecordBytes > file_size)
      throw Error(path, fmt::format("trixel {} points past the end of the file ({} records at byte {})", t.id,
                                    t.count, t.offset));
  }

  constexpr double kPi = std::numbers::pi;
  std::vector<unsigned char> buffer;
  int64_t record = 0;
  for (const Trixel& t : index) {
    if (t.count == 0) continue;
    buffer.resize(size_t(t.count) * kRecordBytes);
    in.seekg(t.offset);
    r.Bytes(buffer.data(), buffer.size(), "star records");
    for (uint32_t k = 0; k < t.count; ++k) {
      ++record;
      const unsigned char* p = buffer.data() + size_t(k) * kRecordBytes;
      const double v_mag = r.At<int16_t>(p + 24) / mag_scale;
      if (!select.KeepMagnitude(v_mag)) continue;
      const double ra_h = r.At<int32_t>(p + 0) / ra_scale;
      const double dec_deg = r.At<int32_t>(p + 4) / dec_scale;
      if (!(ra_h >= 0.0 && ra_h < 24.0) || std::abs(dec_deg) > 90.0)
        throw Error(path, fmt::format("record {} (trixel {}): RA {} h / Dec {} deg out of range", record, t.id,
                                      ra_h, dec_deg));
      CatalogStar s;
      s.ra_rad = ra_h * kPi / 12.0;
      s.dec_rad = dec_deg * kPi / 180.0;
      s.pm_ra_mas_yr = r.At<int32_t>(p + 8) / pmra_scale;
      s.pm_dec_mas_yr = r.At<int32_t>(p + 12) / pmdec_scale;
      MoveToJ2000(&s);
      if (!select.KeepPosition(s.ra_rad, s.dec_rad)) continue;
      const int32_t hd = r.At<int32_t>(p + 20);
      s.id_is_hd = hd > 0;
      s.id = s.id_is_hd ? hd : record;
      s.parallax_mas = r.At<int32_t>(p + 16) / plx_scale;
      s.v_mag = v_mag;
      s.bv_mag = r.At<int16_t>(p + 26) / bv_scale;
      for (int c = 28; c < 30; ++c)
        if (p[c] > ' ' && p[c] < 127) s.spectral_type.push_back(static_cast<char>(p[c]));
      out->push_back(std::move(s));
    }
  }
  if (record == 0) throw Error(path, "no star records in the binary catalog");
}

}  // namespace platemeter::calib::detail
