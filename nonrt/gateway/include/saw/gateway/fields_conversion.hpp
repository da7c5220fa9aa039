// FieldsConv: the conversion of a type that declares its `fields`, to the message of the same members.
#pragma once

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>

#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <vector>

#include "saw/gateway/typed_mapping.hpp"
#include "saw/value_check.hpp"

namespace saw::gateway {

// For a plain rt type whose `fields` (saw/value_check.hpp) are its message's members in the IDL's
// order and of the same types — numbers, booleans, fixed arrays of them (`double x[3]` for a
// Vec3) — after the message's optional std_msgs/Header:
//   struct Spring { ... double stiffness, max_force;
//                   static constexpr auto fields = std::tuple{&Spring::stiffness, &Spring::max_force}; };
//   @final struct Spring { std_msgs::msg::Header header; double stiffness; double max_force; };
// The members are carried through their CDR form (the same bytes both ways), so no conversion is
// written by hand; a sample from a peer is checked with saw::check_value (every number finite, a
// bool 0 or 1, the type's `valid`; a refusal quotes the type's optional `range`, a text saying
// what `valid` wants). Text is the numbers in order ("300 1.5"). Registered with
// MappingRegistry::add_fields<Rt, PubSub>(), which refuses a message whose members do not carry
// the fields (another count or type); two members of one type swapped it cannot see.
template <class Rt, class Msg>
struct FieldsConv {
  static_assert(
      requires { Rt::fields; }, "FieldsConv needs Rt::fields, every member in the message's order");

  template <class F>
  static void each_scalar(F&& f, const Rt& v) {
    std::apply([&](auto... m) { (visit(f, v.*m), ...); }, Rt::fields);
  }
  template <class F>
  static void each_scalar(F&& f, Rt& v) {
    std::apply([&](auto... m) { (visit(f, v.*m), ...); }, Rt::fields);
  }

  static void each(const Rt& v, std::vector<double>& o) {
    each_scalar([&](const auto& x) { o.push_back(static_cast<double>(x)); }, v);
  }

  static void to_msg(const Rt& v, Msg& m) {
    eprosima::fastcdr::FastBuffer out;
    eprosima::fastcdr::Cdr w(out, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    if constexpr (requires { m.header(); }) m.header().serialize(w);
    std::apply([&](auto... f) { (w << ... << (v.*f)); }, Rt::fields);
    eprosima::fastcdr::FastBuffer in(out.getBuffer(), w.getSerializedDataLength());
    eprosima::fastcdr::Cdr r(in, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
    m.deserialize(r);  // add_fields made sure the members match: nothing to throw here
  }

  static bool from_msg(const Msg& m, Rt& v, std::string& why) {
    Rt read{};
    if (!unpack(m, read, why)) return false;
    if (!saw::check_value(read)) {
      why = "a number is not finite, or a value is outside its type's range";
      if constexpr (requires { Rt::range; }) why += " (" + std::string(Rt::range) + ")";
      return false;
    }
    v = read;
    return true;
  }

  // The message's members into `read`, unchecked (add_fields' probe of the layout; a peer's
  // sample goes through from_msg).
  static bool unpack(const Msg& m, Rt& read, std::string& why) {
    try {
      eprosima::fastcdr::FastBuffer out;
      eprosima::fastcdr::Cdr w(out, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
      m.serialize(w);
      eprosima::fastcdr::FastBuffer in(out.getBuffer(), w.getSerializedDataLength());
      eprosima::fastcdr::Cdr r(in, eprosima::fastcdr::Cdr::DEFAULT_ENDIAN, eprosima::fastcdr::Cdr::DDS_CDR);
      if constexpr (requires { m.header(); }) {
        std::remove_cvref_t<decltype(m.header())> header;
        header.deserialize(r);
      }
      std::apply([&](auto... f) { (r >> ... >> (read.*f)); }, Rt::fields);
    } catch (const eprosima::fastcdr::exception::Exception& e) {
      why =
          std::string("the message does not carry ") + std::string(type_info_of<Rt>().name) + ": " + e.what();
      return false;
    }
    return true;
  }

  static std::string text(const Rt& v) {
    std::string s;
    each_scalar(
        [&](const auto& x) {
          char b[32];
          std::snprintf(b, sizeof b, "%.6g", static_cast<double>(x));
          s += (s.empty() ? "" : " ") + std::string(b);
        },
        v);
    return s;
  }

  static bool parse(std::string_view t, Rt& v, std::string& why) {
    const auto n = convert::numbers(t, why);
    if (!why.empty()) return false;
    std::size_t want = 0;
    each_scalar([&](const auto&) { ++want; }, v);
    if (!convert::count_is(n, {want}, why)) return false;
    std::size_t i = 0;
    bool ok = true;
    each_scalar(
        [&](auto& x) {
          using X = std::remove_cvref_t<decltype(x)>;
          if constexpr (std::is_floating_point_v<X>) {
            x = static_cast<X>(n[i]);
          } else if constexpr (std::is_same_v<X, bool>) {
            ok = ok && (n[i] == 0 || n[i] == 1);
            x = n[i] != 0;
          } else {
            ok = ok && n[i] == std::floor(n[i]) && std::abs(n[i]) < 9e15;
            x = static_cast<X>(n[i]);
          }
          ++i;
        },
        v);
    if (!ok) why = "a flag is 0 or 1, a count a whole number";
    return ok;
  }

 private:
  template <class F, class X>
  static void visit(F& f, X& x) {
    if constexpr (requires { std::tuple_size<std::remove_cvref_t<X>>::value; })
      for (auto& e : x) visit(f, e);
    else
      f(x);
  }
};

template <class Rt, class PubSub>
void MappingRegistry::add_fields() {
  using Msg = typename PubSub::type;
  using Conv = FieldsConv<Rt, Msg>;
  // A probe of distinct numbers through the message and back: a message with other members (a
  // count, a type) loses or garbles them, or runs out of bytes. Unchecked: the probe's numbers
  // need not be within the type's range (its `valid`).
  Rt probe{};
  double next = 1;
  Conv::each_scalar(
      [&](auto& x) {
        using X = std::remove_cvref_t<decltype(x)>;
        x = std::is_same_v<X, bool> ? static_cast<X>(static_cast<int>(next) % 2) : static_cast<X>(next);
        next += 1;
      },
      probe);
  Rt back{};
  std::string why;
  bool same = false;
  try {
    Msg m;
    Conv::to_msg(probe, m);
    if (Conv::unpack(m, back, why)) {
      std::vector<double> a, b;
      Conv::each(probe, a);
      Conv::each(back, b);
      same = a == b;
    }
  } catch (const eprosima::fastcdr::exception::Exception& e) {
    why = e.what();
  }
  if (!same)
    throw std::invalid_argument(std::string(type_info_of<Rt>().name) + " and " + PubSub().getName() +
                                ": the message's members (after its header) are not the type's fields, in "
                                "order and of the same types" +
                                (why.empty() ? std::string() : " (" + why + ")"));
  add<Rt, PubSub, Conv>();
}

}  // namespace saw::gateway
