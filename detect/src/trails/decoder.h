#pragma once
// The trail decoder (LinkTrails, trail_linker.h; docs/trails.md): one object per plate holding what its steps
// share, each step a method in a file of its own, in the order Decode runs them:
//   DecodeRuns        decoder_runs.cpp        1-2. leading-dash runs, numbered by their length, grown both ways
//   Settle            decoder_settle.cpp      3.   a trail's sidereal fit and crowded-field checks (every step's
//                                                  trails pass it)
//   CheckNumbers      decoder_numbers.cpp     4.   joins into stars; numbers confirmed or refused
//   GrowSiblings      decoder_siblings.cpp    5.   neighbours of decoded trails grown across the breaks
//   SeparatorTrails   decoder_separators.cpp  6.   trails grown from a separator dash, numbered by a sibling
//   FlowTrails        decoder_flow.cpp        7.   the plate's flow: missing trails, new stars, lone trails,
//                     decoder_flow_fill.cpp        and exposures filled along it
//   DropMergedImages  decoder_merged.cpp      8.   images holding more light than their star's exposure
//   FormStars         decoder.cpp                  the result's stars and counts
// Tags are given and taken back only by Tag, Untag and Refuse (decoder.cpp); the result's counts are counted
// from the tags at the end (CountTags), so no step keeps a count of its own.
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "platemeter/detect/sky_flow.h"
#include "trail_internal.h"

namespace platemeter::trail_internal {

class TrailDecoder {
 public:
  TrailDecoder(const std::vector<DetectedStar>& images, const DutyCycleScheduleOptions& program,
               const TrailOptions& options, const ScanPixels* scan);
  TrailLinkResult Decode();

 private:
  using Taken = std::vector<std::pair<int, int>>;  // (exposure index in the trail, image)

  // What the decoder knows of a chain besides its TrailChain (chain_[k] goes with result_.chains[k]).
  struct ChainState {
    Taken kept;              // its tagged images, exposure order (empty when refused)
    Track track;             // its sidereal track (Settle)
    double flux_per_s = 0;   // the star's flux per second of exposure (DN/s)
    // A run's: the place one dash before it, its dash spacing, its dashes' mean flux and length, and whether
    // an image there may hold a dash (its number then needs a sibling's confirmation, step 4).
    PixelPoint before_px;
    double spacing_px = 0, dash_flux_dn = 0, dash_length_px = 0;
    double run_angle_rad = 0;  // the run's direction (its dashes' sweep)
    int first_dash_image = -1;  // the image of the run's first dash
    bool before_occupied = false;
    bool run_merged = false;  // a dash of the run holds another image's light: the count may join two stars' runs
    Taken grown;             // a run's images as grown (steps 1-2), before Settle
    // Stars as a union-find over chains: the parent, and at a root the trail numbers (bit t: trail t + 1) held.
    int parent = 0;
    unsigned numbers = 0;
  };
  // A decoded trail's track under another trail number (its images re-timed), for step 4.
  struct Retimed {
    bool ok = false;
    Track track;
    double t0_s = 0, t1_s = 0;  // its images' first and last re-timed mid times
  };
  // Step 4's findings.
  struct NumberCheck {
    std::vector<int> decoded;                           // the chains decoded so far
    std::vector<std::vector<Retimed>> retimed;          // [chain][trail number - 1]
    std::vector<bool> doubtful, joined;
    std::vector<std::pair<int, int>> joins;             // (earlier trail, later trail) on one arc
    std::vector<std::vector<int>> partner_count;        // [chain][trail number]: joins with trails of that number
  };

  // Steps (see the file comment).
  void DecodeRuns();
  void DecodeRun(const std::vector<int>& run);
  bool Settle(int cid, const Taken& taken, int min_images = 0);
  bool DropUnverifiable(int cid, Taken* kept, double median_residual_px, int min_images);
  bool TwoStarsOnOnePath(int cid) const;
  void CheckNumbers();
  NumberCheck RetimeTracks() const;
  void FindJoins(NumberCheck* nc) const;
  void ConfirmNumbers(NumberCheck* nc);
  bool ConfirmedAlone(int k);
  void GrowSiblings();
  void SeparatorTrails();
  void JoinSeparatorTrail(int cid, int number, const SiblingGrowth& grown);
  void FlowTrails();
  bool FitFlow();
  void CheckTrailsOnFlow();
  void CheckJoinsOnFlow();
  void CheckSeparatorStars();
  void AddFlowStar(const FlowStar& star, double rate_px_per_s, int root);
  void ForMissingTrails(const std::function<void(int root, int s, int k, double t_end_s, const PixelPoint& origin)>& fn);
  void CompleteStars();
  std::vector<int> FlowSeeds() const;
  DashPlaces PlacesOfReading(int dash, double seed_s, const std::vector<Taken>& taken, double flux_per_s,
                             int max_empty = std::numeric_limits<int>::max()) const;
  TagOf TagOfImages() const;  // each image's tag (trail number, mid-time), for the empty places
  bool RivalLikelier(int dash, const DashPlaces& own, const std::vector<double>& rival_seeds_s,
                     const std::vector<Taken>& taken, double flux_per_s) const;
  bool ReadingRefuted(int dash, double seed_s, const std::vector<Taken>& taken, double flux_per_s);
  bool LoneNumberRefuted(int dash, const LoneTrail& lone, double seed_s, const std::vector<Taken>& taken);
  int FlowPlaceImage(const FlowPath& path, double dt_s, const PixelPoint& origin, const ShutterExposure& e,
                     double flux_per_s) const;
  void FillTrailsAlongFlow();
  void FillMissingSiblings();
  void DropMergedImages();
  void RefitWithout(int k, const Taken& kept);
  void FormStars();

  // Chains and stars.
  int PushChain(const TrailChain& tc);
  int OpenChain(TrailStep step, int s, double flux_per_s, double rate_px_per_s);
  bool AddChain(TrailStep step, int s, const Taken& taken, double flux_per_s, double rate_px_per_s, int missed,
                int min_images = 0);
  bool Decoded(int k) const { return result_.chains[k].trail > 0 && !chain_[k].kept.empty(); }
  int Root(int k);
  void Unite(int child_root, int root);  // child_root's star joins root's, its numbers too
  void Ends(int k, double* t0_s, double* t1_s) const;  // its tagged images' first and last mid times
  bool OnOneArc(const Track& a, double a1_s, const Track& b, double b0_s) const;
  int NumberOf(const PatternTrail& pt, SiblingGrowth* grown) const;  // NumberBySiblings, decoded trails' images
  int NumberBySiblingsOf(int k) const;  // NumberOf a decoded trail's own images
  bool Excluded(int i) const { return result_.images[i].chain >= 0; }  // taken by a decoded trail

  // Tags: the one place that gives and takes them.
  void Tag(int cid, int j, int i);               // image i as exposure j of chain cid's trail (other fields kept)
  void Untag(int i, TrailReason reason);         // image i back to untagged, with the reason
  void Refuse(int cid, TrailReason reason);      // chain cid refused: its tags taken back, its kept cleared
  void TagFlowChecked(int k, int je, int i, const PixelPoint& q);  // Tag, at its measured position (the flow's)
  void RecountMissed(int k);

  const std::vector<DetectedStar>& images_;
  const DutyCycleScheduleOptions& program_;
  const TrailOptions& o_;
  Context c_;
  int trails_ = 0;
  int reference_ = 0;  // the trail with the most leading dashes: its exposures hold every other trail's
  std::vector<int> usable_ids_, dash_ids_;
  std::optional<Grid> all_, dashes_;  // every image; the elongated ones (runs)
  std::vector<int> owner_count_;      // runs that grew over each image (two: a crossing, neither takes it)
  TrailLinkResult result_;
  std::vector<ChainState> chain_;
  SkyFlow flow_;
};

}  // namespace platemeter::trail_internal
