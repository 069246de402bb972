#include "platemeter/batch/scan_record.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "platemeter/core/error.h"
#include "platemeter/core/log.h"
#include "platemeter/core/atomic_file.h"
#include "platemeter/core/sha256.h"

namespace platemeter {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json Optional(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

std::optional<double> OptionalDouble(const json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return j.at(key).get<double>();
}

}  // namespace

std::string FormatScanRecord(const ScanRecord& r) {
  json j;
  j["format"] = "platemeter-batch-record";
  j["format_version"] = r.format_version;
  j["stem"] = r.stem;
  j["scan"] = r.scan;
  j["status"] = r.status;
  j["reason"] = r.reason;
  if (r.status == "failed") j["failure"] = r.failure.empty() ? "input" : r.failure;
  j["fingerprint"] = r.fingerprint;
  j["scan_sha256"] = r.scan_sha256;
  j["scan_size_bytes"] = r.scan_size_bytes;
  j["scan_mtime_ns"] = r.scan_mtime_ns;
  json overrides = json::array();
  for (const auto& [k, v] : r.overrides) overrides.push_back({{"key", k}, {"value", v}});
  j["overrides"] = overrides;
  j["counts_by_status"] = r.counts_by_status;
  j["counts_by_kind"] = r.counts_by_kind;
  j["reseau_rms_um"] = Optional(r.reseau_rms_um);
  j["scale_x"] = Optional(r.scale_x);
  j["scale_y"] = Optional(r.scale_y);
  j["seconds"] = r.seconds;
  j["finished_utc"] = r.finished_utc;
  json outputs = json::array();
  for (const OutputFile& o : r.outputs) {
    outputs.push_back({{"name", o.name}, {"size_bytes", o.size_bytes}, {"sha256", o.sha256}});
  }
  j["outputs"] = outputs;
  j["report_json"] = r.report_json;
  j["plot_png"] = r.plot_png;
  return j.dump(2) + "\n";
}

ScanRecord ParseScanRecord(const std::string& text, const std::string& subject) {
  try {
    const json j = json::parse(text);
    if (j.value("format", "") != "platemeter-batch-record") throw Error(subject, "not a batch record");
    ScanRecord r;
    r.format_version = j.at("format_version").get<int>();
    if (r.format_version != 1) throw Error(subject, "record format version " + std::to_string(r.format_version) + " is not 1");
    r.stem = j.at("stem").get<std::string>();
    r.scan = j.at("scan").get<std::string>();
    r.status = j.at("status").get<std::string>();
    if (r.status != "ok" && r.status != "failed") throw Error(subject, "status '" + r.status + "' is not ok or failed");
    r.reason = j.at("reason").get<std::string>();
    if (r.status == "failed") {
      r.failure = j.value("failure", "input");
      if (r.failure != "input" && r.failure != "environment") {
        throw Error(subject, "failure '" + r.failure + "' is not input or environment");
      }
    }
    r.fingerprint = j.at("fingerprint").get<std::string>();
    r.scan_sha256 = j.at("scan_sha256").get<std::string>();
    r.scan_size_bytes = j.at("scan_size_bytes").get<uint64_t>();
    r.scan_mtime_ns = j.at("scan_mtime_ns").get<int64_t>();
    for (const json& o : j.at("overrides")) r.overrides.emplace_back(o.at("key").get<std::string>(), o.at("value").get<std::string>());
    r.counts_by_status = j.at("counts_by_status").get<std::map<std::string, int>>();
    r.counts_by_kind = j.at("counts_by_kind").get<std::map<std::string, int>>();
    r.reseau_rms_um = OptionalDouble(j, "reseau_rms_um");
    r.scale_x = OptionalDouble(j, "scale_x");
    r.scale_y = OptionalDouble(j, "scale_y");
    r.seconds = j.at("seconds").get<double>();
    r.finished_utc = j.at("finished_utc").get<std::string>();
    for (const json& o : j.at("outputs")) {
      r.outputs.push_back({o.at("name").get<std::string>(), o.at("size_bytes").get<uint64_t>(), o.at("sha256").get<std::string>()});
    }
    r.report_json = j.at("report_json").get<std::string>();
    r.plot_png = j.at("plot_png").get<std::string>();
    return r;
  } catch (const json::exception& e) {
    throw Error(subject, OneLine(e.what()));
  }
}

std::string ScanFolderName(const std::string& stem) {
  // The longest name measure writes is <stem>.measurements.csv; 255 bytes is Linux's NAME_MAX.
  constexpr size_t kNameMax = 255, kLongestSuffix = sizeof(".measurements.csv") - 1;
  if (stem.size() + kLongestSuffix <= kNameMax) return stem;
  return stem.substr(0, 200) + "~" + Sha256Hex(stem).substr(0, 12);
}

std::string ScanFolder(const std::string& out_dir, const std::string& stem) {
  return (fs::path(out_dir) / ScanFolderName(stem)).string();
}

std::string RecordPath(const std::string& out_dir, const std::string& stem) {
  return (fs::path(ScanFolder(out_dir, stem)) / (ScanFolderName(stem) + ".batch.json")).string();
}

std::optional<ScanRecord> ReadScanRecord(const std::string& path, std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (why) *why = "no record";
    return std::nullopt;
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  try {
    return ParseScanRecord(buffer.str(), path);
  } catch (const Error& e) {
    if (why) *why = e.what();
    return std::nullopt;
  }
}

void WriteScanRecord(const std::string& path, const ScanRecord& record) {
  WriteFileAtomically(path, FormatScanRecord(record));
}

OutputFile DescribeOutput(const std::string& folder, const std::string& name) {
  const fs::path p = fs::path(folder) / name;
  std::error_code ec;
  OutputFile o;
  o.name = name;
  o.size_bytes = fs::file_size(p, ec);
  if (ec) throw Error(p.string(), "cannot read the output (" + ec.message() + ")");
  o.sha256 = Sha256HexOfFile(p.string());
  return o;
}

bool OutputsIntact(const ScanRecord& record, const std::string& folder, std::string* why) {
  for (const OutputFile& o : record.outputs) {
    const fs::path p = fs::path(folder) / o.name;
    std::error_code ec;
    const uint64_t size = fs::file_size(p, ec);
    if (ec) {
      *why = o.name + " is missing";
      return false;
    }
    if (size != o.size_bytes) {
      *why = o.name + " has " + std::to_string(size) + " bytes, the record says " + std::to_string(o.size_bytes);
      return false;
    }
    try {
      if (Sha256HexOfFile(p.string()) != o.sha256) {
        *why = o.name + " changed since it was written";
        return false;
      }
    } catch (const Error& e) {
      *why = e.what();
      return false;
    }
  }
  return true;
}

std::vector<ScanRecord> ReadAllRecords(const std::string& out_dir) {
  std::vector<ScanRecord> records;
  std::error_code ec;
  for (fs::directory_iterator it(out_dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::error_code e;
    if (!it->is_directory(e)) continue;
    const std::string folder_name = it->path().filename().string();
    if (folder_name.empty() || folder_name[0] == '.') continue;
    const std::string path = (it->path() / (folder_name + ".batch.json")).string();
    if (!fs::exists(path, e)) continue;
    std::string why;
    std::optional<ScanRecord> r = ReadScanRecord(path, &why);
    if (!r) {
      Warn(why + " (left out of the summary)");
      continue;
    }
    records.push_back(std::move(*r));
  }
  if (ec) throw Error(out_dir, "cannot list the output folder (" + ec.message() + ")");
  std::sort(records.begin(), records.end(), [](const ScanRecord& a, const ScanRecord& b) { return a.stem < b.stem; });
  return records;
}

}  // namespace platemeter
