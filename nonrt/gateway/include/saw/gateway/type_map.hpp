// TypeMap: how each rt value type travels over DDS (its ROS 2 / CRTK message and conversions).
#pragma once

#include <fastdds/dds/topic/TypeSupport.hpp>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "saw/clock.hpp"
#include "saw/value_check.hpp"

namespace eprosima::fastdds::dds {
class DataWriter;
class DataReader;
}  // namespace eprosima::fastdds::dds

namespace saw::gateway {

// One rt type ↔ one DDS message type. Values are passed as the rt type's bytes (the bridge
// moves bytes; TypeInfo's name says which mapping applies).
class Mapping {
 public:
  enum class Take { none, ok, rejected };

  virtual ~Mapping() = default;
  virtual std::string_view saw_type() const = 0;
  virtual std::uint32_t saw_version() const = 0;  // the rt type's layout version
  virtual std::string_view dds_type()
      const = 0;  // the registered name, e.g. geometry_msgs::msg::dds_::PoseStamped_
  virtual eprosima::fastdds::dds::TypeSupport type_support() const = 0;
  // Converts `value` and writes it; `stamp_ns` (wall clock) goes into the header when the message has one.
  virtual bool write(eprosima::fastdds::dds::DataWriter& w, const void* value, std::int64_t stamp_ns,
                     std::string_view frame_id) const = 0;
  // Takes the next sample into `value`. A sample that is not a valid rt value (NaN, infinite,
  // too many joints, unknown state string) is `rejected`, with the reason in `why`; `value` is
  // then left unspecified and must not be used.
  virtual Take take(eprosima::fastdds::dds::DataReader& r, void* value, std::string& why) const = 0;
  // The rt value as one line of text (sawctl echo).
  virtual std::string to_text(const void* value) const = 0;
  // Parses text (numbers separated by spaces or commas, or a word for states and commands) into
  // a valid rt value, validated as a sample from DDS would be (sawctl call).
  virtual bool from_text(std::string_view text, void* value, std::string& why) const = 0;
  virtual std::size_t size() const = 0;  // of the rt type
  // The numbers of the value a person reads (a pose's position, not its quaternion); nothing for
  // states, buttons and booleans. For messages: what bounds a value is within_limits() below.
  virtual void numbers(const void* value, std::vector<double>& out) const {
    (void)value;
    (void)out;
  }
  // The rt value checked as the bridge's exporter checks it (saw::check_value: every number
  // finite and within `limits`, a pose's orientation as much as its position).
  virtual bool check(const void* value, const Limits& limits) const {
    (void)value;
    (void)limits;
    return true;
  }
};

// Whether `value` is within the bounds a component declares for a command: the one check both
// the gateway and clients (sawctl) make, the bridge's; `why` names the first number outside.
bool within_limits(const Mapping& m, const void* value, const Limits& limits, std::string& why);

// The mappings this process knows: the rt core's types (registered by the gateway itself) and
// those each package adds for its own types, with one line per type
// (`registry.add<Rt, PubSub, Conv>()`, saw/gateway/typed_mapping.hpp) in its registration
// function, loaded as a mapping module (saw/gateway/mapping_plugin.hpp).
class MappingRegistry {
 public:
  // Throws std::invalid_argument when `saw_type` is mapped already to another DDS type; the same
  // mapping again (a module loaded twice) is no change. Mappings sharing one DDS type are found by
  // that type in the order they were added.
  void add(std::unique_ptr<Mapping> m);
  template <class Rt, class PubSub, class Conv>
  void add();  // typed_mapping.hpp
  // Rt's `fields` carried as PubSub's message of the same members, no conversion written by hand
  // (fields_conversion.hpp); throws std::invalid_argument when the members do not match.
  template <class Rt, class PubSub>
  void add_fields();

  // The mapping for an rt type name (TypeInfo::name), or nullptr if it has none.
  const Mapping* find(std::string_view saw_type) const;
  // The mapping whose DDS type is `dds_type` (std_msgs/Empty: a void command's), or nullptr.
  const Mapping* find_by_dds(std::string_view dds_type) const;
  const std::vector<std::unique_ptr<Mapping>>& all() const noexcept { return mappings_; }

 private:
  std::vector<std::unique_ptr<Mapping>> mappings_;
};

// A registry of the rt core's types (the gateway's own, core_mappings.cpp). A program makes its
// registry — no process-wide one — and hands it to what maps values (GatewayConfig::mappings,
// DdsResolver::Options::mappings, sawctl's).
MappingRegistry core_mappings();

// Loads into `registry` every mapping module (lib*.so) of the mapping directory of this
// installation (<libdir>/sawrt/mappings beside bin/, or the build tree's lib/sawrt/mappings), then
// of the directories of $SAW_MAPPING_PATH (colon-separated: a lab's), each directory in name
// order. Throws std::runtime_error naming the module (not a mapping module, another ABI, a type
// mapped twice differently) or a directory that cannot be read.
void load_mapping_modules(MappingRegistry& registry);
// The directories load_mapping_modules() reads.
std::vector<std::string> mapping_directories();

// Whether a read of this type is latched: published on change, kept for late joiners (an
// operating state, a component's description), rather than every row.
bool latched(const Mapping* m);
// Void commands travel as std_msgs/Empty.
const Mapping& empty_mapping();

// Wall-clock ns for a CLOCK_MONOTONIC time (row times are monotonic; ROS headers are wall time).
std::int64_t wall_from_monotonic(TimeNs monotonic);

}  // namespace saw::gateway
