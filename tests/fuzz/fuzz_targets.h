#pragma once
// One function per reader for the fuzz harness (docs/fuzzing.md): each calls
// the reader on `bytes` and lets platemeter::Error (the expected rejection)
// through. Where the format has a writer, what was read is written and read
// back: a file the reader accepts but the writer refuses (or that reads back
// differently) throws std::logic_error, a finding like a crash.
#include <string>
#include <vector>

#include "fuzz/fuzz_driver.h"

namespace platemeter::fuzz {

void FuzzMeasurementFile(const std::string& bytes);
void FuzzDefinitions(const std::string& bytes);
void FuzzJobFile(const std::string& bytes);
void FuzzPasspointList(const std::string& bytes);
void FuzzObservationsCsv(const std::string& bytes);
void FuzzGroundPointsCsv(const std::string& bytes);
void FuzzScanManifest(const std::string& bytes);  // with the job overrides it carries
void FuzzStellarJob(const std::string& bytes);
void FuzzBundleJob(const std::string& bytes);
void FuzzTiffHeader(const std::string& bytes);    // Image::Open and a few window reads

// Every reader, in the order above.
const std::vector<FuzzTarget>& AllTargets();
const FuzzTarget& TargetNamed(const std::string& name);

// The seed inputs of a reader: tests/fuzz/corpus/<name>/seed* files (plus the
// built-in definitions for "definitions", small TIFFs written now for "tiff_header").
std::vector<std::string> SeedsOf(const FuzzTarget& target);

}  // namespace platemeter::fuzz
