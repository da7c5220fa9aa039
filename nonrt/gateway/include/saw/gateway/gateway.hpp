// Gateway: maps components exported through the shared-memory bridge to DDS topics.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "saw/clock.hpp"
#include "saw/gateway/participant.hpp"

namespace saw::gateway {

class MappingRegistry;

// A foreign CRTK arm (a dVRK master published by the dVRK's ROS 2 stack) to present through
// the bridge as component `component`, provided interface "arm", read-only.
struct ImportConfig {
  std::string component;                           // its name on this host, e.g. "MTML"
  std::string ros_namespace;                       // "" or e.g. "dvrk": topics rt/<ns>/<arm>/measured_cp, ...
  std::string arm;                                 // e.g. "MTML"
  std::string clutch_topic = "rt/console/clutch";  // sensor_msgs/Joy; "" for none
  std::string operator_present_topic = "rt/console/operator_present";  // sensor_msgs/Joy; "" for none
  // Read-write (settings.hpp's ImportSettings says each): the commands it may send, its safe
  // command (never "": settings derive it) and how long its client may stay silent.
  std::vector<std::string> commands;
  std::string safe_command;
  TimeNs command_timeout = 50'000'000;
  TimeNs offset = 0;  // its cycle's phase, ns into the host's 1 ms grid
};

// A live plot redrawn at 20–25 Hz loses nothing it can show at 50 samples/s.
inline constexpr double default_display_rate = 50;

struct GatewayConfig {
  std::vector<std::string> attach;  // exported component names ("/saw.<name>" segments)
  std::vector<ImportConfig> imports;
  // Components served by gateways on other hosts, to present on this host (one connect(),
  // three distances): each becomes a local component exported through this host's bridge.
  // "NAME" or "NAME=LOCAL" (exported here as LOCAL).
  std::vector<std::string> mirrors;
  ParticipantConfig dds;
  unsigned decimation = 1;  // publish state every Nth row of the server's task
  // Live views (sawgui) need a picture, not every row: each row-by-row state is also published
  // on <topic>/display at this rate (Hz, by the rows' own times; 0: not at all), so that ten
  // GUIs cost the gateway's CPU 50 samples/s each per topic rather than 1,000.
  double display_rate = default_display_rate;
  TimeNs attach_timeout = 0;  // wait this long for a component to be exported (0: fail at once)
  std::string name;           // unique per host; default "gateway.<pid>"
  // The types it maps; none: the rt core's alone (core_mappings()). saw-gateway adds the
  // installation's mapping modules (load_mapping_modules).
  std::shared_ptr<const MappingRegistry> mappings;
};

// One row of the manifest: how a command or event of an attached component is mapped.
struct EndpointInfo {
  std::string component, interface_name, name, kind;
  std::string saw_type;  // the value's rt type name ("" for none)
  std::uint32_t saw_size = 0, saw_version = 0;
  std::string dds_type, topic;  // "" when not mapped
  std::string result_type;      // a qualified read's result
  std::uint32_t result_size = 0, result_version = 0;
  bool limited = false;  // a write command's declared bounds on each of its numbers
  double limit_min = 0, limit_max = 0;
  // Published on change and kept for late joiners (TRANSIENT_LOCAL): an operating state, a
  // description, the read-back `X` of a setting `set_X`. Its readers ask for TRANSIENT_LOCAL.
  bool latched = false;
  // A row-by-row state's display stream (GatewayConfig::display_rate): its topic and rate.
  std::string display_topic;
  double display_rate = 0;
  std::string label() const {  // "Pose v1"
    return saw_type.empty() ? "" : saw_type + " v" + std::to_string(saw_version);
  }
};

struct GatewayStats {
  std::uint64_t published = 0;  // state samples written (full rate)
  std::uint64_t displayed = 0;  // state samples written on the display streams
  // Rows of a server's state the gateway never published: overwritten in the bridge's history
  // (ExportOptions::history_rows) before it read them. Fewer behind than that, it loses none.
  std::uint64_t rows_skipped = 0;
  std::uint64_t events = 0;    // events written
  std::uint64_t commands = 0;  // commands from DDS passed to the bridge
  std::uint64_t rejected = 0;  // commands from DDS refused (invalid value, full ring, server gone)
  std::uint64_t reconnects = 0;
  std::uint64_t queries = 0;            // qualified reads answered
  std::uint64_t imported = 0;           // samples taken from imported arms' topics
  std::uint64_t imported_rejected = 0;  // of which not valid values (dropped, counted)
  // measured_cp samples stamped 0 (the dVRK's invalid data) or not newer than the last (dropped).
  std::uint64_t imported_bad_stamps = 0;
  std::uint64_t arm_commands = 0;       // commands written to imported arms
  std::uint64_t arm_safe_commands = 0;  // of which the imports' own safe commands (client silent)
  std::uint64_t mirrored = 0;           // state samples taken for mirrored components
};

class Attachment;
class ImportedArm;

// An ordinary (non-RT) process's object. Per attached component, one thread: it sleeps on the
// bridge's update bell, publishes the read commands' values (best effort, keep last 1) every
// `decimation` rows and, for live views, at `display_rate` on <topic>/display, publishes events (reliable),
// and passes commands arriving from DDS — validated first — into the bridge. Operating states are latched
// (transient local, keep last 1) and published at attach time, so a late joiner sees them at once. Each
// gateway publishes its manifest on `rt/saw/manifest` (reliable, transient local), and republishes it with
// state FAULT when a server stops.
class Gateway {
 public:
  explicit Gateway(GatewayConfig config);  // throws std::runtime_error naming what failed
  ~Gateway();
  Gateway(const Gateway&) = delete;
  Gateway& operator=(const Gateway&) = delete;

  const std::vector<EndpointInfo>& endpoints() const noexcept { return endpoints_; }
  GatewayStats stats() const;
  const std::string& name() const noexcept { return config_.name; }

  // Called by attachments when a server's liveness changes.
  void publish_manifest();
  // Before a gateway leaves because its RT process died: FAULT with `why` on every attached
  // component's operating state and error topic, acknowledged by the readers (at most `wait`),
  // so peers see FAULT and its reason rather than only a participant gone.
  // (Samples not acknowledged when the participant goes are lost to that reader; but a reader
  // that left without a goodbye never acknowledges, and peers see the gateway gone only after
  // the wait: 300 ms.)
  void announce_exit(const std::string& why, TimeNs wait = 300'000'000);

 private:
  GatewayConfig config_;
  struct Dds;
  std::unique_ptr<Dds> dds_;
  std::vector<EndpointInfo> endpoints_;
  std::vector<std::unique_ptr<Attachment>> attachments_;
  struct Imports;
  std::unique_ptr<Imports> imports_;
  std::mutex manifest_mutex_;
};

}  // namespace saw::gateway
