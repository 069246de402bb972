#pragma once
// Star catalog reader for the KStars star files shipped by Debian's kstars-data
// (Hipparcos/Tycho-derived, ICRS, positions at epoch J2000.0, proper motions).
// Two layouts exist and both are read (detected from the file's content):
//
// 1. Text ("stars.dat" in kstars-data 3.6): '#' comment lines, then one star
//    per line, fixed columns (1-based), sorted roughly by magnitude:
//      1-9   RA  hhmmss.ss          11-19 Dec sddmmss.s
//      21-29 pmRA  mas/yr, INCLUDES cos(dec) (Hipparcos mu_alpha*)
//      30-38 pmDec mas/yr           39-45 parallax mas
//      46-51 V mag                  52-56 B-V mag      57-58 spectral type
//      59-   multiplicity flag, variability; after the first ',' the
//            genitive name and the common name, comma separated (optional).
//    No HD numbers: the id is the 1-based record number in the file.
// 2. Binary KStars "starData" file (namedstars.dat, unnamedstars.dat, and
//    stars.dat in some KStars versions), little-endian:
//      0     124 bytes  free-text description ("KStars Star Data v1.0 ...")
//      124   int16      endianness marker 0x4B53 (bytes 'S','K' on disk)
//      126   uint8      format version (1)
//      127   uint16     number of field descriptors (11)
//      129   16 bytes each: char name[10], uint8 size, uint8 type, int32 scale
//            RA 4 (scale 1e6: hours), Dec 4 (1e5: deg), dRA 4 (10: mas/yr,
//            includes cos dec), dDec 4 (10), parallax 4 (10: mas), HD 4,
//            mag 2 (100), bv_index 2 (100), spec_type char[2], flags 1, unused 1
//      then  uint32 number of HTM trixels, then per trixel
//            uint32 id, uint32 byte offset of its records, uint32 record count
//      then  int16 faint magnitude x100, uint8 HTM level, uint16 max stars/trixel
//      then  the 32-byte records at the offsets given by the index.
//    The id is the HD number where the record has one, else the record number.
//    Positions in these files (kstars-data 3.6) are at the Hipparcos epoch
//    J1991.25; the reader moves them to J2000.0 with their proper motions. The
//    stored "mag" is not always Johnson V for the brightest stars (Arcturus
//    0.16 against V = -0.05): prefer the text stars.dat when V matters.
// Files are streamed record by record; only the selected stars are kept.
#include <cstdint>
#include <string>
#include <vector>

namespace platemeter::calib {

struct CatalogStar {
  int64_t id = 0;             // HD number if `id_is_hd`, else 1-based record number in the file
  bool id_is_hd = false;
  double ra_rad = 0.0;        // ICRS right ascension at `epoch_jyear` (J2000.0 from the reader)
  double dec_rad = 0.0;       // ICRS declination at `epoch_jyear`
  double pm_ra_mas_yr = 0.0;  // proper motion in RA, INCLUDING the cos(dec) factor (mu_alpha*)
  double pm_dec_mas_yr = 0.0; // proper motion in Dec
  double parallax_mas = 0.0;  // 0 when the catalog gives none
  double radial_velocity_km_s = 0.0;  // positive receding; the KStars files give none (0)
  double epoch_jyear = 2000.0;        // Julian epoch (TDB) of ra/dec
  double v_mag = 0.0;                 // visual magnitude
  double bv_mag = 0.0;                // B-V colour, 0 if unknown
  std::string spectral_type;          // two characters such as "A0", "K?"; empty if absent
  std::string name;                   // common or genitive name when the text file gives one
};

struct StarQueryOptions {
  double faint_limit_mag = 9.0;  // keep stars with V <= this
  bool whole_sky = true;         // false: keep only the cone below
  double center_ra_rad = 0.0;    // cone centre (catalog frame, J2000 positions)
  double center_dec_rad = 0.0;
  double radius_rad = 0.0;       // cone radius, 0..pi

  bool Check(std::string* why) const;
};

// Debian's kstars-data location.
std::string DefaultStarCatalogPath();  // "/usr/share/kstars/stars.dat"

// Stars of a KStars catalog file matching `query`, in file order. Throws
// platemeter::Error(path, reason) for a missing, unreadable or malformed file.
std::vector<CatalogStar> LoadStarCatalog(const std::string& path, const StarQueryOptions& query);

// The key of a star in platemeter's files: "HD<n>" for an HD number, else
// "KS<record>" (the kstars record number).
std::string CatalogStarKey(const CatalogStar& star);

// Angular distance between two directions, rad (numerically safe at all separations).
double AngularSeparation(double ra1_rad, double dec1_rad, double ra2_rad, double dec2_rad);

// Seeded random star field: the fallback when a test needs stars but no catalog.
struct RandomStarFieldOptions {
  uint64_t seed = 1;                // same seed, same field
  int count = 1000;                 // number of stars
  double center_ra_rad = 0.0;       // cone centre
  double center_dec_rad = 0.0;
  double radius_rad = 0.5;          // cone radius (uniform on the sphere inside it), 0..pi
  double bright_mag = 2.0;          // magnitude range; counts rise ~ x3.5 per magnitude (star-count slope)
  double faint_mag = 9.0;
  double pm_sigma_mas_yr = 20.0;    // Gaussian sigma of each proper-motion component
  double parallax_max_mas = 20.0;   // uniform parallax in 0..this

  bool Check(std::string* why) const;
};
std::vector<CatalogStar> GenerateRandomStarField(const RandomStarFieldOptions& options);

}  // namespace platemeter::calib
