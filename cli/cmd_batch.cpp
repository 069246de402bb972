// platemeter batch INPUT_DIR|MANIFEST -o OUT (--camera NAME | --job JOB.toml): every scan of an
// archive measured (RunMeasure) into OUT/<stem>/, resumable, shardable, with a summary CSV and an
// HTML index (docs/batch.md). Thin over batch/: the plan and the work (measure_batch.h), the run loop.
#include <sched.h>

#include <csignal>
#include <filesystem>
#include <iostream>
#include <optional>
#include <thread>

#include "commands.h"
#include "platemeter/batch/batch_run.h"
#include "platemeter/batch/interrupt.h"
#include "platemeter/batch/measure_batch.h"
#include "platemeter/batch/shard.h"
#include "platemeter/batch/summary.h"
#include "platemeter/core/error.h"
#include "platemeter/grids/registry.h"
#include "platemeter/pipeline/job_file.h"

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

// The cores this process may run on (a Slurm task's allocation, taskset), not the machine's.
int UsableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
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
  std::optional<DefinitionRegistry> registry;
  MeasureBatchPlan plan;
  MeasureBatchRequest request;
  request.input = args.input;
  request.recursive = args.recursive;
  request.out_dir = args.out_dir;
  request.definition_files = global.definition_files;
  try {
    request.shard = ParseShard(args.shard);
    registry = DefinitionRegistry::Load(global.definition_files);
    pipeline::JobDefinition& base = request.job;
    if (!args.job_file.empty()) base = pipeline::LoadJobFile(args.job_file);
    // Flags given with --camera or --job override the job's values, as for measure --job.
    if (!args.camera.empty()) base.measure.detect.camera = args.camera;
    if (!args.orientation.empty()) pipeline::ApplyJobOverride(base, "orientation", args.orientation);
    if (!args.temperature_degC.empty()) pipeline::ApplyJobOverride(base, "temperature_degC", args.temperature_degC);
    if (!args.pixel_size_um.empty()) pipeline::ApplyJobOverride(base, "pixel_size_um", args.pixel_size_um);
    if (args.allow_ambiguous) base.measure.detect.allow_ambiguous = true;
    plan = PlanMeasureBatch(request);
  } catch (const Error& e) {
    Fail(kExitUsage, e.what());
  }
  const std::vector<BatchItem>& items = plan.items;
  const Shard& shard = request.shard;

  BatchOptions options;
  options.out_dir = args.out_dir;
  options.jobs = args.jobs > 0 ? args.jobs : UsableCores();
  options.force = args.force;
  options.retry_failed = args.retry_failed;
  std::cerr << "batch: " << items.size() << " scans";
  if (shard.count > 1) std::cerr << " (shard " << shard.index << "/" << shard.count << " of " << plan.listed << ")";
  std::cerr << ", " << options.jobs << " at a time, into " << args.out_dir << "\n";

  const ScanWork work = MeasureScanWork(plan, *registry);
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
