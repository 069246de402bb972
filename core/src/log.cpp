#include "platemeter/core/log.h"

#include <iostream>
#include <mutex>

namespace platemeter {
namespace {
std::mutex& SinkMutex() {
  static std::mutex mutex;
  return mutex;
}
LogSink& Sink() {
  static LogSink sink;
  return sink;
}
}  // namespace

void SetWarningSink(LogSink sink) {
  std::lock_guard<std::mutex> lock(SinkMutex());
  Sink() = std::move(sink);
}

void Warn(const std::string& message) {
  std::lock_guard<std::mutex> lock(SinkMutex());
  if (Sink()) {
    Sink()(message);
  } else {
    std::cerr << "warning: " << message << '\n';
  }
}

}  // namespace platemeter
