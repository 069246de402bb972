#pragma once
// The contract between the simulator's geometry (spec -> where every mark lands
// on the scan) and its image formation (marks -> pixels). The geometry fills a
// Scene; the renderer turns it into pixels band by band and computes each
// mark's Cramer-Rao bound. Everything here is in scan pixels (DESIGN.md
// convention: x = column, y = row, centre of the top-left pixel at (0, 0)).
#include <cstdint>
#include <string>
#include <vector>

#include "platemeter/core/pixel.h"

namespace platemeter::sim {

enum class MarkKind {
  kReseauCross,  // reseau cross of the master grid
  kFiducial,     // fiducial mark (cross, dot, ring or format corner)
  kPasspoint,    // marked passpoint (dot or ring)
  kStar,         // point image (PSF)
  kTrailDot,     // a star image exposed while the star moves (PSF swept along a segment)
  kTrailDash,    // a 20 s dash of a duty-cycle trail (same model, longer segment)
  kFalseMark,    // a cross-like mark that is not part of any definition
  kDust,         // defect: a blob
  kScratch,      // defect: a thin line
};
const char* MarkKindName(MarkKind kind);

enum class MarkShapeKind { kCross, kDot, kRing, kCorner, kPsf, kSegment };

// One mark as it lands on the scan. Shapes are defined in the mark's own frame
// in micrometres (u right, v up on the plate) and mapped to pixels by the local
// affine map of the whole geometry chain at the mark's centre, so scanner
// rotation, scale, non-orthogonality and mirroring shape the mark exactly.
struct SceneMark {
  std::string id;
  MarkKind kind = MarkKind::kReseauCross;
  MarkShapeKind shape = MarkShapeKind::kCross;
  PixelPoint centre_px;           // true centre on the scan
  double px_from_um[4] = {0.2, 0, 0, -0.2};  // row-major 2x2: d(x_px,y_px)/d(u_um,v_um) at the centre
  double line_width_um = 20.0;    // cross/ring line width; corner line width; scratch width
  double size_um = 600.0;         // cross arm tip to tip; dot/ring outer diameter; corner arm length
  double corner_angle_rad = 0.0;  // corner: direction of the corner's bisector in the mark frame
  double psf_fwhm_um = 15.0;      // star/trail: FWHM of the Gaussian PSF on the plate (before scanner blur)
  double segment_u_um = 0.0;      // trail dot/dash: motion during the exposure, start -> end, centred on centre_px
  double segment_v_um = 0.0;
  double amplitude_dn = -1000.0;  // peak contrast against the local background (negative: dark mark)
                                  // for kPsf/kSegment: the total flux in DN * px^2 (sign as above)
  double damage_fraction = 0.0;   // 0..1 of the mark's area removed (damaged crosses), deterministic by seed
  uint64_t seed = 0;              // for deterministic damage patterns
};

// What fills the space between marks, and the recording chain after it.
struct SceneBackground {
  double level_dn = 30000.0;          // mean background
  double terrain_amplitude_dn = 0.0;  // smooth terrain-like field (0: flat sky)
  double terrain_scale_px = 400.0;    // typical size of terrain features
  double vignetting_fraction = 0.0;   // fall-off at the format corner relative to the centre (seed 001: up to 0.12)
  PixelPoint optical_centre_px;       // centre of the vignetting
  double vignetting_radius_px = 1.0;  // radius where the fall-off reaches vignetting_fraction
};

struct SceneNoise {
  double scanner_blur_sigma_px = 0.0;  // Gaussian scanner PSF
  double sensor_sigma_dn = 0.0;        // additive Gaussian noise
  double grain_sigma_dn = 0.0;         // film grain: Gaussian, spatially white at the scan resolution
  bool quantize = true;                // round to the sample type on output
  double saturation_dn = 65535.0;      // clip level (also the sample type's full scale)
  uint64_t seed = 1;                   // noise is a deterministic function of (seed, pixel)
};

struct Scene {
  long width_px = 0;
  long height_px = 0;
  SceneBackground background;
  SceneNoise noise;
  std::vector<SceneMark> marks;
};

}  // namespace platemeter::sim
