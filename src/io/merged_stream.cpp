#include "io/merged_stream.hpp"

#include <algorithm>

namespace eds {

MergedStream::MergedStream(const Sequence& seq, std::size_t max_chunk, bool with_events)
    : seq_(seq), source_(with_events && seq.hasEvents() ? seq.openEvents() : nullptr), max_chunk_(max_chunk) {
  pending_.reserve(max_chunk_);
}

bool MergedStream::fillPending() {
  if (pending_pos_ < pending_.size()) return true;
  if (!source_) return false;
  pending_.clear();
  pending_pos_ = 0;
  if (source_->read(pending_, max_chunk_) == 0) {
    source_.reset();
    return false;
  }
  return true;
}

MergedStream::Kind MergedStream::next(EventArray& events, std::size_t& frame_index) {
  const auto& frames = seq_.frames();
  const bool have_events = fillPending();
  const bool have_frame = next_frame_ < frames.size();
  if (!have_events && !have_frame) return Kind::kEnd;
  if (have_frame && (!have_events || pending_.t[pending_pos_] > frames[next_frame_].t)) {
    frame_index = next_frame_++;
    return Kind::kFrame;
  }
  // Events up to (and including) the next frame's time, at most what is pending.
  std::size_t stop = pending_.size();
  if (have_frame) {
    const auto first = pending_.t.begin() + static_cast<std::ptrdiff_t>(pending_pos_);
    stop = static_cast<std::size_t>(std::upper_bound(first, pending_.t.end(), frames[next_frame_].t) -
                                    pending_.t.begin());
  }
  events.clear();
  const auto b = static_cast<std::ptrdiff_t>(pending_pos_), e = static_cast<std::ptrdiff_t>(stop);
  events.t.assign(pending_.t.begin() + b, pending_.t.begin() + e);
  events.x.assign(pending_.x.begin() + b, pending_.x.begin() + e);
  events.y.assign(pending_.y.begin() + b, pending_.y.begin() + e);
  events.p.assign(pending_.p.begin() + b, pending_.p.begin() + e);
  pending_pos_ = stop;
  return Kind::kEvents;
}

}  // namespace eds
