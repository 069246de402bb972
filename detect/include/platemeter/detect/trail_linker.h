#pragma once
// Duty-cycle star trails (seed 001, Table 1; core/duty_cycle.h): the images of
// one star exposed by the capping-shutter program lie along its diurnal arc.
// LinkTrails (docs/trails.md)
//   1. finds the runs of leading dashes: elongated images equally spaced and
//      collinear (30 s apart; with measured lengths, spacing = 1.5 x a dash's
//      length). A run's length N numbers the trail (trail t has
//      leading_dashes[t]); a run is refused when the position one dash before
//      it is off the scan (at_edge); an image there that could hold a dash
//      (a dash not seen as one would change N) leaves the number to the
//      sibling check of step 4 (image_before_run when unconfirmed). With
//      measured segments a dash's neighbours lie along its own direction; two
//      candidates on a side (a crossing) link nothing;
//   2. grows each run, in both time directions, exposure by exposure along
//      the trail: a smooth track position(mid time) fitted to the images taken
//      so far predicts the next exposure; the one image within the tolerance
//      is taken, none (a missing dot) skips the exposure, two or more
//      (a stray beside the dot) leave it untaken. The direction that
//      reaches at least min_exposures_after_run exposures is the trail's; both
//      or neither: unassigned with a reason. No guessing: a dot is either
//      tagged with its trail, dot index and mid-time or left unassigned;
//   3. fits each trail's images with its sidereal track (x and y polynomials of
//      degree track_degree in the mid-exposure time, weighted by the images'
//      sigmas): each image gets a residual, outliers are flagged bad, and every
//      image gets the fitted position at its mid time with a formal sigma;
//   4. joins the trails of one star: trail A's track extrapolated to trail B's
//      images (and B's back to A's) must land within the join tolerance, with
//      one partner only; a star with two trails of one number is split again.
//      Both tracks re-timed under every other pair of trail numbers: two trails
//      that meet under numbers other than their own (a first leading dash lost
//      without trace makes trail N+1 look like trail N) are refused
//      ("doubtful_number"). A lone trail (no other trail of its star decoded)
//      cannot be checked so: require_joined refuses those too.
//   5. grows, from every trail so decoded, its neighbours (trails t - 1, t + 1)
//      whose own runs were not found: the track carried across the break (a
//      parabola beyond the images) predicts the neighbour's exposures, each
//      image within the sibling tolerance; the grown trail passes step 3 and
//      must join its source (step 4); it seeds its own neighbours in turn;
//   6. seeds a trail with no decoded sibling at one of its separator dashes
//      (the dash's length gives the speed, its angle the direction, its flux
//      the star's flux per second; each separator in each direction, exactly
//      one reading must grow) and numbers it by the sibling it grows under
//      exactly one trail number (a sibling on the arc, well fitted); then
//      step 5 again from these;
//   7. fits the plate's flow (detect/sky_flow.h: every star image moves with
//      one velocity field) to the decoded tracks; collects decoded stars'
//      missing trails along it; reads every unassigned dash as each exposure
//      of the program it may be and decodes its star when exactly one reading
//      lines up its images in two trails (docs/trails.md, "The plate's flow").
// Crowded fields (docs/trails.md): the run's and every taken image's flux must
// fit the exposure's duration; an established track takes only images within
// its prediction; trails off most of their images, images off the track amid
// other images and images the track merely follows are refused; and a trail's
// number must be confirmed by a join, or by a sibling grown from its track
// under its number and no other, or by a clean field around its run (outside
// the exposed format, exposed_outline_px, counts as unknown; a slow star's
// unresolved run never is clean). Unassigned with a reason is fine; wrong is not.
#include <string>
#include <vector>

#include "platemeter/core/duty_cycle.h"
#include "platemeter/core/pixel.h"
#include "platemeter/detect/scan_pixels.h"
#include "platemeter/detect/star_detector.h"

namespace platemeter {

// Why an image is not tagged (or, bad_fit, tagged but flagged bad); why a run or trail was refused. The
// measurement file writes the name (TrailReasonName) as the image's `trail:<name>` flag (docs/trails.md).
enum class TrailReason {
  kNone,
  kNotStar,                  // not a measured star image (rejected, a defect)
  kUnlinked,                 // no trail took it
  kAtEdge,                   // its run may continue off the scan or the format
  kImageBeforeRun,           // an image where a dash before the run would be
  kShortPattern,             // too few exposures after the run in either direction
  kAmbiguous,                // both directions grow
  kContested,                // taken by two trails
  kLeadingDashesIncomplete,  // a run of a length no trail has
  kDoubtfulNumber,           // two trails meet under numbers other than their own
  kLoneTrail,                // nothing else of its star decoded to confirm its number
  kPoorTrack,                // the track fit failed or kept too few images
  kUnconfirmed,              // no sibling or clean field confirms its number
  kRunFlux,                  // the run's dashes' fluxes differ
  kOffTrack,                 // off its track amid other stars' images
  kUnverified,               // the track merely follows it (leverage)
  kBlended,                  // flux not its exposure's: a dash unlike its run, an image merged with another
  kUnjoined,                 // a grown sibling that does not join its source
  kUnresolvedRun,            // a slow star's run whose dashes merge
  kOffFlow,                  // a trail off the plate's flow
  kEmptyPlaces,              // its star's reading predicts dashes where the plate shows none (a separator star)
  kBadFit,                   // tagged, its position an outlier of the track fit
};
const char* TrailReasonName(TrailReason reason);  // "not_star", ...; "" for kNone

// The step that decoded a trail.
enum class TrailStep { kRun, kSibling, kSeparators, kFlow, kLone, kFlowFill };
const char* TrailStepName(TrailStep step);  // "run", "sibling", "separators", "flow", "lone", "flow_fill"

struct TrailOptions {
  // The plate (the caller knows it).
  double psf_fwhm_px = 2.5;            // px; the PSF's FWHM (length comparisons: a point image measures 0)
  double max_dash_spacing_px = 200.0;  // px; longest spacing of two leading dashes (30 s x the fastest rate)
  // The scanned area (px). A trail whose leading run starts near its edge may have lost dashes
  // beyond it (trail 3 minus one dash looks like a complete trail 2): the position one dash before
  // the run must lie inside by edge_margin_px, else the run is refused. Unset (max <= min):
  // no check, the caller guarantees that trails are not cut by the scan's edge.
  PixelPoint image_min_px{0.0, 0.0};
  PixelPoint image_max_px{0.0, 0.0};
  double edge_margin_px = 10.0;        // px
  // The exposed format's outline (a convex polygon, px; a plate is exposed only inside its format, often
  // smaller than the scan): the same checks as the scanned area. Empty: the scanned area alone.
  std::vector<PixelPoint> exposed_outline_px;
  // Where the star detector was blind (its StarMask: the reseau crosses' arms): an image touching it was
  // lost in the cross, so no place there is empty and no run is known to start beside it.
  StarMask blind;
  // What the user decides.
  bool require_joined = false;         // true: a trail is tagged only when joined to another trail of its star
                                       // (which confirms its number); lone trails stay unassigned ("lone_trail")
  // Tolerances a plate may need changed (its measuring precision, photometry, distortion).
  double match_tolerance = 0.25;       // fraction of the smaller neighbouring exposure spacing (px) a taken image
                                       // may lie off its predicted position
  double flux_tolerance = 0.3;         // fraction; an image taken as exposure e must hold the run's flux per second x
                                       // e's duration within this (plus 4 sigma); 0: fluxes not compared
  double position_floor_px = 0.02;     // px; added in quadrature to the images' formal sigmas (weights)
  int track_degree = 3;                // degree of the fitted track polynomials (3: the arc's curvature over 25 min)
  double join_tolerance_px = 1.0;      // px; trails are joined into stars when their tracks meet within this
                                       // (plus tuning.join_tolerance_fraction of the extrapolation distance)
  double flow_tolerance_px = 0.4;      // px; an image predicted by the plate's flow must lie within this (plus
                                       // tuning.flow_tolerance_fraction of its distance from the image it was
                                       // predicted from)

  // The decoder's internal constants (docs/trails.md): each comment says what the value rests on. Tests and
  // benchmarks may change them; a plate should not need to. (The fixed counts of evidence the flow's readings
  // must show are in detect/src/trails/evidence.h.)
  struct Tuning {
    double run_spacing_tolerance = 0.2;  // fraction; leading dashes' spacings may differ from their mean by this
    double max_run_bend_deg = 10.0;      // deg; largest turn between consecutive leading dashes
    double min_tolerance_px = 1.5;       // px; the match tolerance never drops below this
    int min_exposures_after_run = 11;    // a trail must take this many exposures past its leading run
    int max_missed_in_row = 12;          // growth stops after this many consecutive exposures without an image
    double min_elongated_exposure_s = 5.0;  // s; an image flagged elongated only matches exposures this long
    double dash_length_tolerance = 0.3;  // fraction; an image with a measured length_px must match the exposure's
                                         // duration x rate within this (plus psf_fwhm_px), when length_px > 0
    double bad_sigma = 5.0;              // an image whose residual exceeds this many sigmas (the sigma scaled by the
                                         // fit's robust spread when that exceeds 1) is flagged bad and left out
    double min_bad_px = 0.25;            // px; residuals below this are never bad (model floor)
    double join_tolerance_fraction = 0.005;  // of the extrapolation distance (a 30 s error in timing, one trail
                                         // number off, misses by 30 s x the rate: 4-15 px)
    // Crowded fields (docs/trails.md, "Crowded fields"): what a trail must prove before it is tagged.
    double max_median_residual_px = 0.15;  // px; a grown trail whose good images' median track residual exceeds
                                         // this (or max_median_residual_fwhm x psf_fwhm_px) took other stars'
                                         // images: refused
    double max_median_residual_fwhm = 0.08;
    double run_flux_tolerance = 0.3;     // fraction; a run's dashes (equal exposures) must have equal fluxes within
                                         // this (plus 4 sigma): a stray dash of another star would change N
    double crowd_radius_fwhm = 10.0;     // a bad image with another star's image within this many FWHM is not
                                         // tagged ("off_track": likely that star's); alone it stays tagged, bad
    double tight_tolerance_px = 0.3;     // px; with other images near (crowded), an image off the established
                                         // track by more than this (and 5 sigma of the prediction) is not taken
    double max_leverage = 0.8;           // an image the track follows this much (hat-matrix diagonal) is not tagged
    int min_sibling_images = 5;          // raw images on a sibling trail's predicted exposures that confirm a number
    double sibling_window_s = 600.0;     // s; sibling exposures compared: within the break plus this of its end
    double sibling_tolerance_px = 0.5;   // px; a sibling exposure's image must lie within this plus
    double sibling_tolerance_fraction = 0.002;  // this fraction of the extrapolation distance (correct joins:
                                         // 0.01-0.45 px; under a wrong number the prediction lands 10 s x the
                                         // rate off a sibling's dot)
    double clean_radius_spacings = 1.0;  // a trail confirmed by no sibling is kept only when no other image lies
                                         // within this many dash spacings of the position one dash before its run
    // Siblings grown from decoded trails (docs/trails.md, "Siblings").
    double sibling_growth_window_s = 1500.0;  // s; the growing track is fitted to the images within this
    // Trails grown from their separator dashes (docs/trails.md, "Separators").
    double motion_radius_px = 400.0;     // px; decoded trails within this give the local direction of motion
    // The plate's flow (docs/trails.md, "The plate's flow").
    int flow_degree = 6;                 // polynomial degree of the velocity field (the Orbigon's distortion: 6)
    double flow_tolerance_fraction = 2e-4;  // of the distance a flow prediction is carried
    int flow_min_images = 8;             // images a trail found along the flow must hold (a new star: two trails)
    int flow_min_sibling_images = 6;     // images a decoded star's missing trail found along the flow must hold
  } tuning;

  // Test-only seam: the decoder's later steps and checks, each switched off by an ablation test that measures
  // what it adds (tests/detect/trail_crowded_test.cpp). Users leave them on.
  struct Ablation {
    bool grow_siblings = true;         // step 5: siblings grown from decoded trails
    bool pattern_trails = true;        // step 6: trails grown from their separator dashes
    bool flow_trails = true;           // step 7: the plate's flow (and everything below)
    bool flow_lone_trails = true;      // a star with one trail on the format numbered by its run found along the
                                       // flow (not with require_joined: nothing else confirms the number)
    bool flow_fills_trails = true;     // each decoded trail's exposures without an image filled along the flow
                                       // (beyond the growth's or the track's reach): one compatible image within
                                       // flow_tolerance_px (in a gap inside: also within tight_tolerance_px of
                                       // the track), tagged at its measured position
    bool flow_fills_siblings = true;   // a decoded star's trails still missing filled the same way, exposure by
                                       // exposure from its trail nearest in time (at least 3 images)
    bool flow_entering_trails = true;  // such a trail entering the format (its run beyond it) numbered by its other
                                       // trails' absence: the one number under which none of them lies on the
                                       // format where nothing is (docs/trails.md, "Trails entering the format")
    bool flow_cut_trails = true;       // such a trail cut by the format's edge (leaving it after its first dot
                                       // groups, entering it for its last) needs only the exposure durations it
                                       // shows on the format, at least 3, instead of 4 (docs/trails.md, "Trails
                                       // cut by the format's edge")
    bool flow_crowded_readings = true;  // where a crowd hides a star's dashes (not a slow star's): a reading's
                                       // second trail needs no dash when its images sit at its first trail's
                                       // offset (within 0.15 px) with 5 dots of 2 groups; the seed's flux is
                                       // shown by 5 other dashes and 3 durations, or 1 dash and 5 durations
                                       // (4 with the images' flux per second the seed's) (docs/trails.md,
                                       // "The plate's flow" 4)
    bool flow_blended_seeds = true;    // a dash fitted jointly with a neighbour (blended: its flux is not the
                                       // star's) seeds too (not a slow star's): each reading takes the star's
                                       // flux per second from its own images, then needs the usual evidence
                                       // (docs/trails.md, "The plate's flow" 4)
    bool flow_lone_held_dashes = true;  // a lone trail's run goes on over a dash's place held by an image not
                                       // measured as that dash (merged, cut, shaped wrong) where the place
                                       // before it holds one of the run's dashes (docs/trails.md, "The
                                       // plate's flow" 5)
    bool flow_empty_places = true;     // a flow or lone reading refused when its dash places the plate shows empty
                                       // make it 100 times likelier wrong than right (docs/trails.md, "Empty
                                       // dash places")
    bool two_stars = true;             // a trail whose dots are longer than their sweeps is two stars on one path
                                       // (docs/trails.md, "Settle")
  } ablation;
  bool Check(std::string* why) const;  // every setting, tuning included
};

// The outcome for one input image (same order as the input).
struct TrailImage {
  int chain = -1;                  // decoded trail (index into TrailLinkResult::chains), -1 if none
  int star = -1;                   // star (index into TrailLinkResult::stars) of assigned images, -1 otherwise
                                   // (a trail joined to no other is a star of its own)
  bool assigned = false;           // true: trail/kind/indices/mid_s are valid
  int trail = 0;                   // 1..number of trails (T1..T4), in time order
  ExposureKind kind = ExposureKind::kDot;
  int dot_index = 0;               // 1..25 for dots
  int dash_index = 0;              // 1.. for dashes (leading dashes first, then the separators)
  double mid_s = 0.0;              // s; mid-exposure, on the scale of DutyCycleScheduleOptions::start_s
  bool bad = false;                // assigned, but its position disagrees with the trail's track (outlier)
  bool flow_checked = false;       // found along the plate's flow beyond the growth's or the track's reach:
                                   // refined_px is its measured position, residual the flow's
  bool forced = false;             // not detected: measured at its track's prediction (trail_forced.h);
                                   // refined_px is its measured position, residual the prediction's
  double residual_x_px = 0.0;      // px; measured minus fitted track position (assigned images)
  double residual_y_px = 0.0;      // px
  double residual_px = 0.0;        // px; length of the residual
  PixelPoint refined_px;           // px; the fitted track at mid_s (assigned images; flow_checked: measured)
  double sigma_refined_x_px = 0.0; // px; formal sigma of refined_px (scaled by the fit's reduced chi^2 when > 1;
                                   // flow_checked: the measured sigma with position_floor_px)
  double sigma_refined_y_px = 0.0; // px
  TrailReason reason = TrailReason::kNone;  // why not assigned; for bad (still assigned) images: kBadFit
};

// One leading-dash run and the trail grown from it.
struct TrailChain {
  std::vector<int> images;         // input indices in time order (taken images only)
  int trail = 0;                   // decoded trail 1..4, 0 if refused
  int leading_dashes = 0;          // dashes in the run
  int star = -1;                   // index into TrailLinkResult::stars, -1 if not decoded
  double rate_px_per_s = 0.0;      // px/s; speed along the track at its end (linear fit)
  double rms_px = 0.0;             // rms residual of the track fit (good images)
  int bad_images = 0;              // images flagged bad by the track fit
  int missed_exposures = 0;        // exposures of the trail's span without an image taken
  TrailReason reason = TrailReason::kNone;  // kNone if decoded, else why refused
  TrailStep decoded_by = TrailStep::kRun;  // the step that found it (kFlowFill: no track, its images flow_checked)
};

// The trails of one star (same diurnal arc, one after another).
struct TrailStar {
  std::vector<int> chains;         // indices into TrailLinkResult::chains, in trail order
};

struct TrailLinkResult {
  std::vector<TrailImage> images;  // one per input image
  std::vector<TrailChain> chains;  // decoded trails and refused runs
  std::vector<TrailStar> stars;    // trails joined into stars (a lone trail is a star of its own)
  long assigned_dots = 0;
  long assigned_dashes = 0;
  long bad_images = 0;             // assigned images flagged bad
  // Readings refused for their empty dash places (docs/trails.md "Empty dash places"): flow and lone readings
  // (counted per seed tried) and stars of separator trails.
  long refused_readings = 0;
  // "D dots and L dashes tagged in T trails of S stars (B bad); R runs refused".
  std::string Summary() const;
};

// Links and decodes the trails. `program` is the plate's shutter program with
// start_s = the first opening on the caller's time scale. Images that are not
// measured stars (rejected, defects) are left unassigned ("not_star").
// Uses DetectedStar::length_px when set (trail-mode detection). Throws Error
// for invalid options.
// `scan`, where given, lets a lone trail's run be counted in the pixels where detections cannot say
// (docs/trails.md, "The run in the pixels").
TrailLinkResult LinkTrails(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
                           const TrailOptions& options = {}, const ScanPixels* scan = nullptr);

}  // namespace platemeter
