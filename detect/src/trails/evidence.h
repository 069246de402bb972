#pragma once
// The evidence the flow's readings must show (trail_flow.cpp DecodeByFlow, trail_lone.cpp DecodeLoneTrail,
// decoder_flow_fill.cpp): the decoder's fixed counts in one place, each with what its value rests on. The
// tolerances and thresholds that tests and benchmarks vary are TrailOptions::Tuning (trail_linker.h).
// "The whole V <= 8 plate" is the benchmark plate (bench_trails, docs/trails.md); the counts were set there
// and hold on the plate family's other plates (bench_trails --family).
#include <algorithm>
#include <cmath>

namespace platemeter::trail_internal {

// --- A reading's own trail and its flux
// Images of the reading's own trail near the seed that let the rest of the plate be searched (most wrong
// readings of most dashes stop here: a wrong reading finds little near the seed).
inline constexpr int kOwnTrailImages = 3;
// Images with a flux a blended seed's reading needs to take the star's flux per second from them (a median
// of fewer is one image's flux).
inline constexpr int kMinFluxImages = 5;
// Dashes besides the seed, and exposure durations among the images (of the program's six): a reading shifted
// by a dot group maps the dots onto other durations; the flux tolerance (a faint dot's sigma) lets some of
// those through (on the whole V <= 8 plate: 1.2 s dots read as 0.6 s ones, 10 s as 6.2 s), not all.
inline constexpr int kOtherDashes = 2, kDurations = 4;

// --- DecodeByFlow: a star with two trails or more
// A slow star (10 s of motion, the shift between some readings, within kSlowTolerances flow tolerances): a
// wrong reading lands near its own images, so it must show the kSlow* counts (with the usual ones the whole
// V <= 8 plate had 19 wrong tags, a lone trail read under another number with 4 chance dots of a "second
// trail").
inline constexpr double kSlowTolerances = 4.0;
inline constexpr int kSlowFirst = 12, kSlowSecondTrailDots = 8, kSlowDurations = 5;
// Decoded: a trail of flow_min_images and this many dots of a second trail (a wrong reading lines up one trail
// of the star and at most 2 dots of any other: the trails' dot programs are shifted 30 s against each other,
// sky_flow_test's schedule check).
inline constexpr int kSecondTrailDots = 4;
// A candidate (a second one makes the decision ambiguous): a trail of 5 and 3 dots of another.
inline constexpr int kCandidateFirst = 5, kCandidateDots = 3;
// A seed may be two stars' dashes merged: its readings are also tried with this share of its flux (two dashes
// of like flux; the flux tolerance covers shares of about 0.35-0.65), as candidates only.
inline constexpr double kMergedSeedShare = 0.5;
// An image's flux above its star's flux per second x its exposure length by more than this share (and 4 of
// its flux sigmas) holds another image's light (decoder_merged.cpp). The plate-wide ratio of an image's flux
// to its trail's flux per second x length has a p10-p90 spread of -2..+1 % for 20 s dashes and -4..+2 % for
// 10 s dots (Miami): 10 % is several times that. The images so taken back were right to 1.5 px but far off
// their sigmas (Denver: RMS(error / sigma) about 16 over 2049 such dots); 10, 15 and 25 % tagged the same
// measurable dots right (+-2 on each tuning plate), and left Miami 0, 1 and 2 wrong tags.
inline constexpr double kMergedFluxExcess = 0.10;
// A star's trails' fluxes per second (each the median over its images) agree to this share, beyond their
// sigmas: on the benchmark plate, of 6554 pairs of one star's trails, 90 % within 3.6 %, 99 % within 11 %
// (2026-12-07). Another star on the same diurnal path differs by its magnitude (Cairo's KS4270 and KS5615:
// 0.25 mag, 26 %).
inline constexpr double kStarFluxSpread = 0.10;
// Whether an image of flux_dn (sigma_flux_dn) holds more than expect_dn by that share and 4 sigmas.
inline bool HoldsMergedLight(double flux_dn, double sigma_flux_dn, double expect_dn) {
  return expect_dn > 0 && flux_dn - expect_dn > kMergedFluxExcess * expect_dn + 4.0 * sigma_flux_dn;
}
// A flow trail's images that its track merely follows (leverage) still count towards flow_min_images (the
// flow found each at its place); its track must keep this many of its own (a parabola's 3 with 3 to check it).
inline constexpr int kMinFlowTrackImages = 6;
// A second trail without a dash of its own counts (crowds hide dashes) with this many dots of two groups at
// the first trail's offset, within kSameOffset_px: the seed's own position error shifts a right reading's
// predictions alike everywhere (whole V <= 8 plate: of 209 unique readings' dashless second trails, 193
// within 0.15 px of their first trail's offset); another star's dots lined up by a wrong reading lie anywhere
// within the tolerance (the one wrong reading of that kind seen there: 0.52 px).
inline constexpr int kDashlessDots = 5;
inline constexpr double kSameOffset_px = 0.15;
// Where the crowd hides the star's other dashes or durations, other proof of the seed's flux (not a slow
// star's): many dashes (5) with 3 durations; one dash with 5 durations, or with kDurations and the images'
// flux per second the seed's (their ratio within kMinFluxRatio .. 1 / kMinFluxRatio; a merged seed reads
// about 0.5).
inline constexpr int kManyDashes = 5, kManyDashesDurations = 3, kOneDashDurations = 5;
inline constexpr double kMinFluxRatio = 0.8;

// --- DecodeLoneTrail: a star with one trail on the format
// A slow star (10 s of motion within this many flow tolerances) is not decoded: readings shifted by 10 s land
// on its own images. (Its run may merge: the merged explanation counts it.)
inline constexpr double kLoneNotDecodedTolerances = 2.0;
// A reading lining up this many dots of another trail makes the star DecodeByFlow's (which left it undecided).
inline constexpr int kOtherTrailDots = 3;
// A group of readings with this many images past the run is a candidate; exactly one may exist.
inline constexpr int kCandidateImages = 5;
// A trail cut by the format's edge: its dashes and at least two dot durations.
inline constexpr int kMinDurationsCut = 3;
// A reading showing this many images of another trail of the star shows that trail.
inline constexpr int kShownImages = 3;
// An empty place of a trail counts where an image of that trail (any star's) is tagged within this (a cloud
// or a shutter fault during one trail empties its places on every star).
inline constexpr double kExposedRadius_px = 150.0;
// Two tags of one exposure have the same mid-time (the program's); any two exposures are 30 s or more apart.
inline constexpr double kSameExposure_s = 1.0;

// --- A reading's empty places (reading_places.cpp; DecodeByFlow's and DecodeLoneTrail's readings)
// The share of a reading's places the plate shows empty, by flux (ReadingPlaces), when the reading is right
// and when it is wrong. Measured on the tuning plates: right readings 0.3-1.1 % of their dash places (a crowd
// hides a dash) and 1.6-2.0 % of their dot places (the benchmark plate and Paris, 2026-12-07: dots the
// detector missed in a crowd), wrong ones 17-43 % (a wrong reading puts its dashes where the star was
// exposed for a dot or not at all). Both rates are set towards each other, so that only clear cases decide.
inline constexpr double kEmptyWhenRight = 0.03, kEmptyWhenWrong = 0.30;
// A reading's dot places count where the dot would be detected at this SNR or more, its flux sigma taken as
// the seed dash's (a dot, shorter, has a smaller one): fainter dots may be missed by the detector.
inline constexpr double kDetectedDotSnr = 10.0;
// A reading is refused when its empty places make it this many times likelier wrong than right (with the
// rates above: 6 of 30 places empty; 5 of 20).
inline constexpr double kRefuteOdds = 100.0;
// An image this many times the dash's flux hides or halves a dash near it (on the benchmark plate and
// Denver, right readings' empty places lay 3-7 px beside images of 4-135 times their dash's flux, their
// dashes missing or measured as points at a third to a half of their flux). Its reach grows with the log of
// the ratio, as a photographic image's diameter grows linearly with magnitude. (Ratio 2 with 2 FWHM per
// decade gave the same figures on the benchmark plate and Miami as 3 with 1.5.)
inline constexpr double kDominatingRatio = 3.0;
inline double DominatedReach_px(double fwhm_px, double flux_ratio) {
  return (2.0 + 1.5 * std::min(3.0, std::log10(flux_ratio))) * fwhm_px;
}

// --- Two stars on one diurnal path (decoder_settle.cpp TwoStarsOnOnePath)
// Two stars on one path a fixed time apart merge at every exposure; one swept PSF fitted to the pair is longer
// than the sweep by about their offset (Lisbon's KS11950 and KS12231, 2.7 px = 1.2 FWHM apart: dots 1.4-2.4
// px too long, 11-28 sigmas each). The median over a trail's dots (3 or more, of a FWHM's sweep or longer)
// exceeds kTwoStarExcessFwhm FWHM and kTwoStarExcessSigmas of its own sigmas. Over every decoded trail (a
// dump on 2026-12-08, two-star trails included) the median excess had p50 0.00 px and p99 0.46-0.55 px
// (Beltsville, Paris, Lisbon, Cairo: 0.2-0.26 FWHM); saturated dots no wider (p99 0.35-0.42 px per dot). A
// companion 1.2 FWHM along the path is caught (TrailLinker.TwoStarsOnOnePathMergedAtEveryExposureAreNoStar);
// one 0.8 FWHM along mostly is not (its blend lies within 0.4 FWHM of either star; 0.4 FWHM would catch
// under half of those).
inline constexpr double kTwoStarExcessFwhm = 0.6;
inline constexpr double kTwoStarExcessSigmas = 5.0;
inline constexpr double kTwoStarMinSweepFwhm = 1.0;
inline constexpr int kTwoStarDots = 3;

// --- A trail on the flow (trail_flow.cpp OnTwoFlowPaths, decoder_flow.cpp CheckTrailsOnFlow)
// Images of a trail a FWHM or more off the flow path through its first image, and as many off the path through
// its last, that make it two stars' (the flow carries an image 3000 px to 0.02 px RMS; a right trail's images lie
// on it to their measuring error, and one the track fit left a FWHM off is flagged bad and not counted).
inline constexpr int kFlowStrayImages = 3;

// --- Filling along the flow
// Images a decoded star's missing trail filled along the flow must hold, of two exposure durations (a single
// image at the flow's tolerance may be a chance coincidence over the thousands of places tried).
inline constexpr int kSiblingFillImages = 3;
// Or this many of one duration: a trail cut by the format's edge may show one dot group only, and five images
// each at its place to the flow's tolerance, of the dot's flux and length, are no chance (2026-12-08: Cairo +28
// right dots, Houston +14, Beltsville +12, no wrong tag on the family; TrailCrowded.AStarsTrailShowingOneDot-
// GroupIsFilledAlongTheFlow).
inline constexpr int kSiblingFillOneDuration = 5;

}  // namespace platemeter::trail_internal
