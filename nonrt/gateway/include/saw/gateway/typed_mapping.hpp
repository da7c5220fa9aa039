// TypedMapping: one rt type carried as one generated DDS message, through a conversion struct.
#pragma once

#include <fastcdr/exceptions/Exception.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <initializer_list>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "saw/crtk.hpp"
#include "saw/gateway/type_map.hpp"
#include "saw/type_info.hpp"

namespace saw::gateway {

// What a conversion struct Conv for rt type Rt and message Msg provides (the rt core's are in
// nonrt/gateway/src/*_conversions.hpp, the teleoperation's in rt/teleop/dds/):
//   static void to_msg(const Rt&, Msg&);                       // header: set by the mapping
//   static bool from_msg(const Msg&, Rt&, std::string& why);   // a peer's sample: check everything
//   static std::string text(const Rt&);                         // one line (sawctl echo)
//   static bool parse(std::string_view, Rt&, std::string& why); // sawctl call's text
// and optionally
//   static void each(const Rt&, std::vector<double>&);          // the numbers a person reads
namespace convert {

inline bool finite(std::initializer_list<double> xs) {
  for (double x : xs)
    if (!std::isfinite(x)) return false;
  return true;
}

template <class V>
void put(const Vec3& a, V& v) {
  v.x(a[0]);
  v.y(a[1]);
  v.z(a[2]);
}
template <class V>
bool get(const V& v, Vec3& a, std::string& why, const char* what) {
  a = {v.x(), v.y(), v.z()};
  if (finite({a[0], a[1], a[2]})) return true;
  why = std::string(what) + " is not finite";
  return false;
}

// Whitespace- or comma-separated numbers ("[1, 2, 3]" too); empty with `why` set on a word that
// is not a number.
inline std::vector<double> numbers(std::string_view t, std::string& why) {
  std::vector<double> v;
  std::string s(t);
  for (char& c : s)
    if (c == ',' || c == '[' || c == ']') c = ' ';
  std::istringstream in(s);
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    const double x = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0') {
      why = "\"" + word + "\" is not a number";
      return {};
    }
    v.push_back(x);
  }
  return v;
}

// Whether `v` has one of the counts `ok`; else `why` (unless set already) says what was expected.
inline bool count_is(const std::vector<double>& v, std::initializer_list<std::size_t> ok, std::string& why) {
  for (auto n : ok)
    if (v.size() == n) return true;
  if (why.empty()) {
    why = "expected ";
    for (auto n : ok) why += std::to_string(n) + (n == *std::prev(ok.end()) ? "" : " or ");
    why += " numbers, got " + std::to_string(v.size());
  }
  return false;
}

inline std::string trimmed(std::string_view t) {
  const auto b = t.find_first_not_of(" \t\n");
  if (b == std::string_view::npos) return "";
  return std::string(t.substr(b, t.find_last_not_of(" \t\n") - b + 1));
}

inline std::string text(const Vec3& v) {
  char b[96];
  std::snprintf(b, sizeof b, "[%.6g, %.6g, %.6g]", v[0], v[1], v[2]);
  return b;
}

// The next valid sample into `m`: false when there is none. A peer's sample that Fast CDR cannot
// read (a bad encapsulation) throws from the generated deserializer inside take_next_sample: it
// is refused here, with the reason, instead of ending the gateway's thread (fuzz: gateway_sample).
template <class Msg>
ReturnCode_t take_next(eprosima::fastdds::dds::DataReader& r, Msg& m, std::string& why) {
  eprosima::fastdds::dds::SampleInfo info;
  for (;;) {
    try {
      const ReturnCode_t rc = r.take_next_sample(&m, &info);
      if (rc != ReturnCode_t::RETCODE_OK || info.valid_data) return rc;  // skip disposal notices
    } catch (const eprosima::fastcdr::exception::Exception& e) {
      why = std::string("malformed sample: ") + e.what();
      return ReturnCode_t::RETCODE_ERROR;
    }
  }
}

}  // namespace convert

// Rt carried as PubSub's message (fastddsgen's PubSubType: its `type` is the message).
template <class Rt, class PubSub, class Conv>
class TypedMapping final : public Mapping {
 public:
  using Msg = typename PubSub::type;

  std::string_view saw_type() const override { return type_info_of<Rt>().name; }
  std::uint32_t saw_version() const override { return type_info_of<Rt>().version; }
  std::string_view dds_type() const override { return name_; }
  eprosima::fastdds::dds::TypeSupport type_support() const override {
    return eprosima::fastdds::dds::TypeSupport(new PubSub());
  }
  std::size_t size() const override { return sizeof(Rt); }

  bool write(eprosima::fastdds::dds::DataWriter& w, const void* value, std::int64_t stamp_ns,
             std::string_view frame) const override {
    Msg m;
    if constexpr (requires { m.header(); }) {
      m.header().stamp().sec(static_cast<std::int32_t>(stamp_ns / 1'000'000'000));
      m.header().stamp().nanosec(static_cast<std::uint32_t>(stamp_ns % 1'000'000'000));
      m.header().frame_id(std::string(frame));
    }
    Conv::to_msg(*static_cast<const Rt*>(value), m);
    return w.write(&m);
  }

  Take take(eprosima::fastdds::dds::DataReader& r, void* value, std::string& why) const override {
    Msg m;
    why.clear();
    if (const ReturnCode_t rc = convert::take_next(r, m, why); rc != ReturnCode_t::RETCODE_OK)
      return why.empty() ? Take::none : Take::rejected;
    Rt v{};
    if (!Conv::from_msg(m, v, why)) return Take::rejected;
    *static_cast<Rt*>(value) = v;
    return Take::ok;
  }

  std::string to_text(const void* value) const override { return Conv::text(*static_cast<const Rt*>(value)); }
  void numbers(const void* value, std::vector<double>& out) const override {
    if constexpr (requires(const Rt& r, std::vector<double>& o) { Conv::each(r, o); })
      Conv::each(*static_cast<const Rt*>(value), out);
  }
  bool check(const void* value, const Limits& limits) const override {
    return saw::check_value(*static_cast<const Rt*>(value), &limits);
  }

  bool from_text(std::string_view text, void* value, std::string& why) const override {
    why.clear();  // (a parser may read a non-empty `why` as its own failure)
    Rt v{};
    if (!Conv::parse(text, v, why)) return false;
    // Through the message and back: the same validation as a sample arriving from DDS.
    Msg m;
    Conv::to_msg(v, m);
    Rt checked{};
    if (!Conv::from_msg(m, checked, why)) return false;
    *static_cast<Rt*>(value) = checked;
    return true;
  }

 private:
  std::string name_ = PubSub().getName();
};

template <class Rt, class PubSub, class Conv>
void MappingRegistry::add() {
  add(std::make_unique<TypedMapping<Rt, PubSub, Conv>>());
}

}  // namespace saw::gateway
