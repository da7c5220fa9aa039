#include "saw/teleop/fault_info.hpp"

#include <charconv>

namespace saw::teleop {

FaultInfo fault_on(FaultSide side, FaultCode code, Status last_read, TimeNs age_ns) noexcept {
  FaultInfo f;
  f.code = code;
  f.last_read = last_read;
  f.age_ns = age_ns;
  f.set_source(to_string(side));
  return f;
}

FaultText& FaultText::append(std::string_view s) noexcept {
  for (const char c : s) {
    if (size == max) break;
    text[size++] = c;
  }
  text[size] = '\0';
  return *this;
}

FaultText& FaultText::append(double v) noexcept {
  char b[32];
  const auto r = std::to_chars(b, b + sizeof b, v);
  return append(r.ec == std::errc{} ? std::string_view(b, static_cast<std::size_t>(r.ptr - b)) : "?");
}

}  // namespace saw::teleop
