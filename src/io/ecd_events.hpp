#pragma once
// Events of the Event Camera Dataset text layout: `t x y p` per line, t in seconds (9 decimals),
// p in {0,1} (also accepted: -1/+1). Plain or gzip-compressed (detected by content, not name).
#include <filesystem>
#include <memory>

#include "io/event_source.hpp"

namespace eds {

class LineReader;

struct EcdEventOptions {
  int width = 0;   // when > 0, x >= width is an error
  int height = 0;  // when > 0, y >= height is an error
};

class EcdEventSource : public EventSource {
 public:
  explicit EcdEventSource(const std::filesystem::path& file, EcdEventOptions opts = {});
  ~EcdEventSource() override;
  std::size_t read(EventArray& out, std::size_t max_events) override;

 private:
  std::unique_ptr<LineReader> reader_;
  EcdEventOptions opts_;
  TimeNs last_t_ = 0;
};

}  // namespace eds
