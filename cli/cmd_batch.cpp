// platemeter batch INPUT_DIR|MANIFEST -o OUT (--camera NAME | --job JOB.toml): every scan of an
// archive measured (RunMeasure) into OUT/<stem>/, resumable, shardable, with a summary CSV and an
// HTML index (docs/batch.md). Thin over batch/ (listing, records, run loop) and measure_run.h.
#include <sched.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "commands.h"
#include "job.h"
#include "measure_run.h"
#include "platemeter/batch/batch_run.h"
#include "platemeter/batch/interrupt.h"
#include "platemeter/batch/scan_list.h"
#include "platemeter/batch/shard.h"
#include "platemeter/batch/summary.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/measure/sha256.h"

namespace platemeter::cli {
namespace {

// Exit codes (docs/batch.md).
constexpr int kExitSomeFailed = 1;
constexpr int kExitUsage = 2;

struct BatchArguments {
  std::string input;  // folder or manifest
  std::string out_dir;
  std::string camera, job_file;
  std::string orientation, temperature_degC, pixel_size_um;
  bool allow_ambiguous = false;
  std::string shard = "1/1";
  int jobs = 0;  // 0: every core
  bool force = false, retry_failed = false, recursive = false, summary_only = false;
};

[[noreturn]] void Fail(int code, const std::string& message) {
  std::cerr << "platemeter: error: " << message << '\n';
  throw CLI::RuntimeError(code);
}

// Outputs also depend on the definition files (a camera's grid, fiducials) and on the passpoint
// list's contents, which the options text names only by path: their digests join the fingerprint.
std::string DefinitionsFingerprintText(const std::vector<std::string>& definition_files) {
  std::ostringstream out;
  std::vector<std::string> files;
  if (const char* list = std::getenv("PLATEMETER_DEFINITIONS")) {
    std::stringstream s(list);
    for (std::string f; std::getline(s, f, ':');) {
      if (!f.empty()) files.push_back(f);
    }
  }
  files.insert(files.end(), definition_files.begin(), definition_files.end());
  for (const std::string& f : files) out << "definitions_sha256 = " << Sha256HexOfFile(f) << "\n";
  return out.str();
}

std::string PasspointListFingerprintText(const MeasureRequest& m) {
  if (!m.detect.passpoints || m.detect.passpoints->list_file.empty()) return "";
  return "passpoint_list_sha256 = " + Sha256HexOfFile(m.detect.passpoints->list_file) + "\n";
}

// The cores this process may run on (a Slurm task's allocation, taskset), not the machine's.
int UsableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

ScanWorkResult ToWorkResult(const MeasureSummary& s) {
  ScanWorkResult r;
  r.counts_by_status = s.counts_by_status;
  r.counts_by_kind = s.counts_by_kind;
  r.reseau_rms_um = s.reseau_rms_um;
  r.scale_x = s.scale_x;
  r.scale_y = s.scale_y;
  r.written_files = s.written_files;
  r.report_json = s.report_json;
  r.plot_png = s.plot_png;
  return r;
}

int SummaryOnly(const BatchArguments& args) {
  std::error_code ec;
  if (!std::filesystem::is_directory(args.out_dir, ec) || ReadAllRecords(args.out_dir).empty()) Fail(kExitUsage, args.out_dir + ": no batch records to summarise");
  const SummaryFiles files = WriteBatchSummary(args.out_dir);
  std::cout << "batch: " << files.scans << " scan records: " << files.ok << " ok, " << files.failed << " failed\n"
            << "summary: " << files.csv_path << "\nindex: " << files.html_path << "\n";
  return files.scans == 0 ? kExitUsage : (files.failed > 0 ? kExitSomeFailed : 0);
}

int RunBatchCommand(const BatchArguments& args, const GlobalOptions& global) {
  if (args.summary_only) {
    if (!args.input.empty()) Fail(kExitUsage, "--summary-only takes no INPUT (it reads the records in OUT)");
    return SummaryOnly(args);
  }
  if (args.input.empty()) Fail(kExitUsage, "batch: INPUT (a folder of scans or a manifest CSV) is required");
  if (args.jobs < 0) Fail(kExitUsage, "--jobs: must be at least 1");

  // Everything that can be wrong with the input is found before the first scan starts.
  std::vector<BatchItem> items;
  std::map<std::string, MeasureRequest> requests;  // by stem
  std::optional<DefinitionRegistry> registry;
  Shard shard;
  size_t listed = 0;
  try {
    shard = ParseShard(args.shard);
    registry = DefinitionRegistry::Load(global.definition_files);
    JobDefinition base;
    if (!args.job_file.empty()) base = LoadJobFile(args.job_file);
    // Flags given with --camera or --job override the job's values, as for measure --job.
    if (!args.camera.empty()) base.measure.detect.camera = args.camera;
    if (!args.orientation.empty()) ApplyJobOverride(base, "orientation", args.orientation);
    if (!args.temperature_degC.empty()) ApplyJobOverride(base, "temperature_degC", args.temperature_degC);
    if (!args.pixel_size_um.empty()) ApplyJobOverride(base, "pixel_size_um", args.pixel_size_um);
    if (args.allow_ambiguous) base.measure.detect.allow_ambiguous = true;

    std::vector<ScanInput> scans = ListScans(args.input, args.recursive, JobOverrideKeys());
    // OUT inside INPUT (with --recursive): its plots are .png files, not scans.
    std::error_code ec;
    const std::string out_prefix = std::filesystem::weakly_canonical(args.out_dir, ec).string() + "/";
    std::erase_if(scans, [&](const ScanInput& s) {
      std::error_code e;
      return std::filesystem::weakly_canonical(s.path, e).string().rfind(out_prefix, 0) == 0;
    });
    if (scans.empty()) throw Error(args.input, "no scan files (.tif .tiff .png .jpg .jpeg .fits .fit)");
    CheckUniqueStems(scans);  // over the whole list, so every shard refuses the same archive
    listed = scans.size();
    const std::string definitions_text = DefinitionsFingerprintText(global.definition_files);
    for (size_t i : ShardPositions(scans.size(), shard)) {
      const ScanInput& scan = scans[i];
      JobDefinition job = base;
      for (const auto& [key, value] : scan.overrides) {
        try {
          ApplyJobOverride(job, key, value);
        } catch (const Error& e) {
          throw Error(args.input, "line " + std::to_string(scan.manifest_line) + ": " + e.reason());
        }
      }
      if (job.measure.detect.camera.empty() && job.measure.detect.grid.empty()) {
        throw Error(scan.path, "no camera: give --camera NAME or --job JOB.toml (or a camera column in the manifest)");
      }
      job.measure.detect.scan = scan.path;
      BatchItem item;
      item.input = scan;
      item.options_text = CanonicalOptionsText(job.measure) + definitions_text + PasspointListFingerprintText(job.measure);
      requests[scan.stem] = job.measure;
      items.push_back(std::move(item));
    }
  } catch (const Error& e) {
    Fail(kExitUsage, e.what());
  }

  BatchOptions options;
  options.out_dir = args.out_dir;
  options.jobs = args.jobs > 0 ? args.jobs : UsableCores();
  options.force = args.force;
  options.retry_failed = args.retry_failed;
  std::cerr << "batch: " << items.size() << " scans";
  if (shard.count > 1) std::cerr << " (shard " << shard.index << "/" << shard.count << " of " << listed << ")";
  std::cerr << ", " << options.jobs << " at a time, into " << args.out_dir << "\n";

  const DefinitionRegistry& reg = *registry;
  const ScanWork work = [&requests, &reg](const BatchItem& item, const std::string& folder) {
    MeasureRequest request = requests.at(item.input.stem);
    request.out_dir = folder;
    return ToWorkResult(RunMeasure(request, reg));
  };
  InstallBatchInterruptHandlers();
  ProgressReporter progress(items.size(), ProgressReporter::IsTerminal(stderr), stderr);
  const BatchOutcome outcome = RunBatch(items, work, options, &progress);
  const SummaryFiles files = WriteBatchSummary(args.out_dir);

  std::cout << "batch: " << outcome.Summary() << "\n";
  for (const std::string& f : outcome.failures) std::cout << "failed: " << f << "\n";
  std::cout << "summary: " << files.csv_path << "\nindex: " << files.html_path << "\n";
  if (outcome.interrupt_signal != 0) {
    std::cerr << "platemeter: batch interrupted (" << (outcome.interrupt_signal == SIGINT ? "SIGINT" : "SIGTERM")
              << "): " << outcome.not_started << " scans not started; rerun the same command to continue\n";
    return 128 + outcome.interrupt_signal;
  }
  return outcome.AllOk() ? 0 : kExitSomeFailed;
}

}  // namespace

void RegisterBatchCommand(CLI::App& app, GlobalOptions& global) {
  auto args = std::make_shared<BatchArguments>();
  auto* cmd = app.add_subcommand("batch",
                                 "measure every scan of a folder or manifest: resumable, shardable, summary CSV and "
                                 "HTML index (docs/batch.md)");
  cmd->add_option("INPUT", args->input, "folder of scans (.tif .tiff .png .jpg .jpeg .fits .fit) or a manifest CSV");
  cmd->add_option("-o,--output", args->out_dir, "output folder: OUT/<stem>/ per scan, batch-summary.csv, index.html")
      ->required();
  cmd->add_option("--camera", args->camera, "camera definition (or `camera` in the job file)");
  cmd->add_option("--job", args->job_file, "job file with every measure option (docs/job.md)")->check(CLI::ExistingFile);
  cmd->add_option("--orientation", args->orientation, "known scan orientation of every scan: 0, 90, 180, 270, with m for mirrored");
  cmd->add_flag("--allow-ambiguous-orientation", args->allow_ambiguous, "accept an undecided orientation");
  cmd->add_option("--temperature-degC", args->temperature_degC, "measuring temperature, degC (thermal scaling)");
  cmd->add_option("--pixel-size-um", args->pixel_size_um, "scan pixel size in um (default: the TIFF tags)");
  cmd->add_option("--shard", args->shard, "K/N: only the scans at positions i with i mod N = K-1 (no coordination)");
  cmd->add_option("-j,--jobs", args->jobs, "scans measured at a time, and threads in all (default: the cores this process may use)");
  cmd->add_flag("--force", args->force, "redo every scan, even those whose outputs are current");
  cmd->add_flag("--retry-failed", args->retry_failed, "redo the scans that failed before with the same input and options");
  cmd->add_flag("-r,--recursive", args->recursive, "also the scans in sub-folders of INPUT");
  cmd->add_flag("--summary-only", args->summary_only, "only rebuild OUT's summary CSV and index from its records");
  cmd->callback([args, &global] {
    const int code = RunBatchCommand(*args, global);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace platemeter::cli
