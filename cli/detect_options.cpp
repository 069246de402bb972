// Detection options of detect and measure (detect_options.h).
#include "detect_options.h"

#include "platemeter/core/error.h"

namespace platemeter::cli {

void AddScanOptions(OptionOverlay<DetectRequest>& o) {
  o.Option("--pixel-size-um", [](DetectRequest& r) -> auto& { return r.pixel_size_um; },
           "scan pixel size in um (default: the TIFF resolution tags; a measurement file's header)");
  o.Option("--orientation", [](DetectRequest& r) -> auto& { return r.orientation; },
           "known scan orientation: 0, 90, 180, 270, with m for mirrored (e.g. 90m)");
  o.Flag("--allow-ambiguous-orientation", [](DetectRequest& r) -> auto& { return r.allow_ambiguous; },
         "write results even when the orientation (hence the ids) cannot be decided");
}

void AddFeatureOptions(OptionOverlay<DetectRequest>& o) {
  o.Flag("--stars", [](DetectRequest& r) -> auto& { return r.stars; }, "also detect star images (kind star; docs/stars.md)");
  o.Flag("--bright-stars", [](DetectRequest& r) -> auto& { return r.stars_bright; },
         "stars are brighter than the background (default: dark, a negative)");
  o.Option("--star-fwhm-px", [](DetectRequest& r) -> auto& { return r.star_fwhm_px; },
           "a star image's FWHM in px to start from; the plate's own stars then give the width at each place (default 2.5)")
      ->check(CLI::Range(0.5, 100.0));

  // Duty-cycle trails (seed 001): giving the start time switches them on. The parsed values live in
  // parsed().trails; a detail applies to the resolved request's trails when it has them.
  TrailRequest& trails = o.parsed().trails.emplace();
  CLI::Option* start = o.command()->add_option(
      "--trails-start-utc", trails.start_utc,
      "link star images into duty-cycle trails; ISO 8601 UTC of the plate's first shutter opening");
  o.OnGiven(start, [&trails](DetectRequest& r) {
    if (!r.trails) r.trails = trails;  // with the details given (or their defaults)
    r.trails->start_utc = trails.start_utc;
  });
  CLI::Option* dashes =
      o.command()->add_option("--trail-dashes", trails.leading_dashes, "leading dashes per trail in exposure order (default 2,3,4,5)")
          ->delimiter(',');
  o.OnGiven(dashes, [&trails](DetectRequest& r) {
    if (!r.trails) throw Error("--trail-dashes", "needs --trails-start-utc (or [trails] in the job file)");
    r.trails->leading_dashes = trails.leading_dashes;
  });
  CLI::Option* break_s = o.command()->add_option("--trail-break-s", trails.break_s, "break between trails in s (default 480)");
  o.OnGiven(break_s, [&trails](DetectRequest& r) {
    if (!r.trails) throw Error("--trail-break-s", "needs --trails-start-utc (or [trails] in the job file)");
    r.trails->break_s = trails.break_s;
  });
  CLI::Option* joined = o.command()->add_flag(
      "--trails-require-joined", trails.require_joined,
      "tag only trails joined to another trail of their star (lone and entering trails stay untagged)");
  o.OnGiven(joined, [](DetectRequest& r) {
    if (!r.trails) throw Error("--trails-require-joined", "needs --trails-start-utc (or [trails] in the job file)");
    r.trails->require_joined = true;
  });

  CLI::Option* no_forced = o.command()->add_flag(
      "--trails-no-forced-dots{false}", trails.forced_dots,
      "do not measure a decoded trail's undetected dots at its track's prediction");
  o.OnGiven(no_forced, [](DetectRequest& r) {
    if (!r.trails) throw Error("--trails-no-forced-dots", "needs --trails-start-utc (or [trails] in the job file)");
    r.trails->forced_dots = false;
  });

  // Passpoints: giving the mark's diameter switches them on.
  PasspointRequest& passpoints = o.parsed().passpoints.emplace();
  CLI::Option* diameter =
      o.command()->add_option("--passpoint-diameter-um", passpoints.diameter_um, "measure passpoints: outer diameter of the mark in um")
          ->check(CLI::PositiveNumber);
  o.OnGiven(diameter, [&passpoints](DetectRequest& r) {
    if (!r.passpoints) r.passpoints = passpoints;
    r.passpoints->diameter_um = passpoints.diameter_um;
  });
  // A detail without the diameter (here or in the job) would be silently ignored: refuse it.
  auto detail = [&o](CLI::Option* option, auto field) {
    o.OnGiven(option, [&o, field, name = option->get_name()](DetectRequest& r) {
      if (!r.passpoints) throw Error(name, "needs --passpoint-diameter-um (or [passpoints] in the job file)");
      field(*r.passpoints) = field(*o.parsed().passpoints);
    });
  };
  detail(o.command()->add_option("--passpoint-shape", passpoints.shape, "dot or ring (default dot)")
             ->check(CLI::IsMember({"dot", "ring"})),
         [](PasspointRequest& p) -> auto& { return p.shape; });
  detail(o.command()->add_option("--passpoint-line-width-um", passpoints.line_width_um, "ring line width in um"),
         [](PasspointRequest& p) -> auto& { return p.line_width_um; });
  detail(o.command()->add_option("--passpoint-polarity", passpoints.polarity, "dark or bright (default dark)")
             ->check(CLI::IsMember({"dark", "bright"})),
         [](PasspointRequest& p) -> auto& { return p.polarity; });
  detail(o.command()->add_option("--passpoints", passpoints.list_file,
                                 "approximate passpoint positions (CSV id,x_px,y_px; docs/passpoints.md); default: find and number them"),
         [](PasspointRequest& p) -> auto& { return p.list_file; });
}

}  // namespace platemeter::cli
