#include "io/ros_events.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "io/libcaer_payload.hpp"
#include "io/prophesee.hpp"

namespace eds {

namespace {

const std::vector<std::string> kEventTypes = {"dvs_msgs/EventArray", "prophesee_event_msgs/EventArray",
                                              "event_camera_msgs/EventPacket"};

}  // namespace

bool isEventTopicType(const std::string& type) {
  return std::find(kEventTypes.begin(), kEventTypes.end(), type) != kEventTypes.end();
}

std::size_t chooseEventTopic(const RosBagReader& bag, const std::string& wanted) {
  const auto topic = chooseTopic(bag, kEventTypes, wanted, "event", "--events-topic");
  if (!topic)
    throw InputError(bag.path(), "no event topic (dvs_msgs/EventArray or event_camera_msgs/EventPacket)");
  return *topic;
}

struct RosEventSource::Impl {
  std::unique_ptr<RosBagReader> bag;
  std::size_t topic;
  bool packets;
  RosEventStats stats;
  Evt3Decoder evt3;
  TimeOrder order;
  bool have_offset = false;
  std::vector<std::uint16_t> words;  // the payload, aligned for the decoder; reused across messages
  std::uint64_t message_index = 0;   // of the message in `pending`, for errors

  Impl(const std::filesystem::path& path, const std::string& wanted)
      : bag(openRosBag(path)),
        topic(chooseEventTopic(*bag, wanted)),
        packets(bag->topics()[topic].type == "event_camera_msgs/EventPacket") {}

  InputError error(const std::string& what) const {
    return InputError(bag->path(), "message " + std::to_string(message_index) + " on " +
                                       bag->topics()[topic].name + ": " + what);
  }

  // Decodes the next message of the topic into `pending`; false at the end of the bag.
  bool refill(EventArray& pending) {
    RosMessage m;
    do {
      if (!bag->next(m)) return false;
    } while (m.topic != topic);
    message_index = m.index;
    RosMessageReader r(m.data, bag->topics()[topic].serialization);
    if (packets)
      decodePacket(r, pending);
    else
      decodeArray(r, pending);
    ++stats.messages;
    checkPixels(pending);
    const std::size_t bad = order.apply(pending, 0);
    if (bad != pending.size())
      throw error("events out of order: event " + std::to_string(bad) + " of the message is " +
                  std::to_string((order.latest() - pending.t[bad]) / 1000) + " us before an earlier one");
    stats.raised = order.raised();
    return true;
  }

  void decodeArray(RosMessageReader& r, EventArray& pending) {
    r.header();
    stats.height = r.u32("height");
    stats.width = r.u32("width");
    const bool ros1 = bag->topics()[topic].serialization == RosSerialization::kRos1;
    // 13 bytes an event at least: ROS 1 packs them; CDR pads each to the alignment of its fields from the
    // message's start, which gives 14 or 16 by turns.
    const std::uint32_t n = r.sequenceLength(13, "events");
    pending.reserve(n);
    if (ros1) {
      decodePackedEvents(r.view().take(13 * static_cast<std::size_t>(n), "events"), n, pending);
      return;
    }
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint16_t x = r.u16("event x"), y = r.u16("event y");
      const TimeNs t = r.time("event ts");
      pending.push_back(t, x, y, r.u8("event polarity") ? 1 : -1);
    }
  }

  // ROS 1 packs each dvs_msgs/Event in 13 bytes: x u16, y u16, sec u32, nsec u32, polarity u8.
  void decodePackedEvents(const ByteView v, std::uint32_t n, EventArray& pending) const {
    const std::uint8_t* e = v.data();
    pending.resize(n);
    for (std::uint32_t i = 0; i < n; ++i, e += 13) {
      std::uint16_t xy[2];
      std::uint32_t ts[2];
      std::memcpy(xy, e, 4);
      std::memcpy(ts, e + 4, 8);
      if (ts[1] >= 1'000'000'000u) throw error("event " + std::to_string(i) + ": nanoseconds out of range");
      pending.t[i] = static_cast<TimeNs>(ts[0]) * kNsPerSec + ts[1];
      pending.x[i] = xy[0];
      pending.y[i] = xy[1];
      pending.p[i] = e[12] ? 1 : -1;
    }
  }

  void decodePacket(RosMessageReader& r, EventArray& pending) {
    const EventPacketMsg p = readEventPacket(r);
    stats.width = p.width;
    stats.height = p.height;
    if (p.big_endian) throw error("big-endian " + p.encoding + " payload");
    if (p.encoding == "libcaer" || p.encoding == "libcaer_cmp") {
      decodeLibcaerPacket(p, pending);
      return;
    }
    if (p.encoding != "evt3")
      throw error("event encoding '" + p.encoding + "' is not read (evt3, libcaer and libcaer_cmp are)");
    if (p.events.size() % 2 != 0) throw error("evt3 payload of an odd number of bytes");
    const std::size_t first_trigger = stats.triggers.size();
    words.resize(p.events.size() / 2);
    if (p.events.size() > 0) std::memcpy(words.data(), p.events.data(), p.events.size());
    try {
      evt3.decode(words.data(), words.size(), pending, stats.triggers);
    } catch (const EvtWordError& e) {
      throw error("evt3 word " + std::to_string(e.word) + " has undefined type " + std::to_string(e.type));
    }
    if (!have_offset && !pending.empty()) {
      stats.sensor_offset = p.stamp - pending.t.front();
      have_offset = true;
    }
    for (TimeNs& t : pending.t) t += stats.sensor_offset;
    for (std::size_t i = first_trigger; i < stats.triggers.size(); ++i)
      stats.triggers[i].t += stats.sensor_offset;
  }

  // libcaer payloads carry their absolute time: time_base is the ROS clock's ns at the packet's base.
  void decodeLibcaerPacket(const EventPacketMsg& p, EventArray& pending) const {
    if (p.time_base > static_cast<std::uint64_t>(std::numeric_limits<TimeNs>::max() / 2))
      throw error("time_base " + std::to_string(p.time_base) + " ns is beyond int64 ns");
    const auto base = static_cast<TimeNs>(p.time_base);
    try {
      if (p.encoding == "libcaer")
        decodeLibcaer(p.events.data(), p.events.size(), base, pending);
      else
        decodeLibcaerCompressed(p.events.data(), p.events.size(), base, pending);
    } catch (const PayloadError& e) {
      throw error(std::string(e.what()) + " (payload byte " + std::to_string(e.byte) + ")");
    }
  }

  void checkPixels(const EventArray& pending) const {
    for (std::size_t i = 0; i < pending.size(); ++i)
      if (pending.x[i] >= stats.width || pending.y[i] >= stats.height)
        throw error("event " + std::to_string(i) + " at pixel (" + std::to_string(pending.x[i]) + ", " +
                    std::to_string(pending.y[i]) + ") outside the message's " + std::to_string(stats.width) +
                    "x" + std::to_string(stats.height) + " sensor");
  }
};

RosEventSource::RosEventSource(const std::filesystem::path& path, const std::string& topic)
    : impl_(std::make_unique<Impl>(path, topic)) {}
RosEventSource::~RosEventSource() = default;
const RosTopic& RosEventSource::topic() const { return impl_->bag->topics()[impl_->topic]; }
const char* RosEventSource::bagFormat() const { return impl_->bag->format(); }
const RosEventStats& RosEventSource::stats() const { return impl_->stats; }

bool RosEventSource::decodeNextBlock(EventArray& block) { return impl_->refill(block); }

}  // namespace eds
