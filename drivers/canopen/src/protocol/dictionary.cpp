#include "saw/canopen/dictionary.hpp"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace saw::canopen {

std::optional<Access> access_from_string(std::string_view s) noexcept {
  if (s.size() > 5) return std::nullopt;
  char buf[6] = {};
  for (std::size_t i = 0; i < s.size(); ++i)
    buf[i] = static_cast<char>(std::tolower(static_cast<unsigned char>(s[i])));
  const std::string_view l(buf, s.size());
  if (l == "ro") return Access::ro;
  if (l == "wo") return Access::wo;
  if (l == "rw") return Access::rw;
  if (l == "rwr") return Access::rwr;
  if (l == "rww") return Access::rww;
  if (l == "const") return Access::const_;
  return std::nullopt;
}

std::string_view to_string(Access a) noexcept {
  switch (a) {
    case Access::ro:
      return "ro";
    case Access::wo:
      return "wo";
    case Access::rw:
      return "rw";
    case Access::rwr:
      return "rwr";
    case Access::rww:
      return "rww";
    case Access::const_:
      return "const";
  }
  return "?";
}

SdoAbort LocalDictionary::check_value(const Entry& e, std::span<const std::uint8_t> data) noexcept {
  const TypeClass c = type_class(e.type);
  if (!is_numeric(c)) {
    if (data.size() > e.capacity) return SdoAbort::length_too_high;
    if (e.type == DataType::visible_string) {
      // ISO 646 printable characters; NUL pads a fixed-size string.
      const bool printable = std::all_of(data.begin(), data.end(),
                                         [](std::uint8_t b) { return b == 0 || (b >= 0x20 && b < 0x7F); });
      if (!printable) return SdoAbort::invalid_value;
    }
    return SdoAbort::none;
  }
  const std::size_t n = size_of(e.type);
  if (data.size() > n) return SdoAbort::length_too_high;
  if (data.size() < n) return SdoAbort::length_too_low;
  Number v;
  if (const Codec codec = decode(e.type, data, v); codec != Codec::ok) return abort_for(codec);
  if (e.low && compare(v, *e.low) < 0) return SdoAbort::value_too_low;
  if (e.high && compare(v, *e.high) > 0) return SdoAbort::value_too_high;
  return SdoAbort::none;
}

void LocalDictionary::add(ObjectAddress address, Entry entry) {
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument("object " + to_string(address) + " '" + entry.name + "': " + what);
  };
  if (entries_.contains(address)) fail("already in the dictionary");
  if (is_numeric(type_class(entry.type))) {
    if (entry.value.size() != size_of(entry.type))
      fail("a " + std::string(to_string(entry.type)) + " value needs " + std::to_string(size_of(entry.type)) +
           " bytes, has " + std::to_string(entry.value.size()));
    if (entry.low && entry.high && compare(*entry.low, *entry.high) > 0) fail("low limit above high limit");
  } else {
    entry.capacity = std::max(entry.capacity, entry.value.size());
    entry.value.reserve(entry.capacity);
  }
  if (const SdoAbort a = check_value(entry, entry.value); a != SdoAbort::none)
    fail("value refused: " + std::string(to_string(a)));
  entries_.emplace(address, std::move(entry));
}

const Entry* LocalDictionary::find(ObjectAddress address) const noexcept {
  const auto it = entries_.find(address);
  return it == entries_.end() ? nullptr : &it->second;
}

bool LocalDictionary::has_index(std::uint16_t index) const noexcept {
  const auto it = entries_.lower_bound(ObjectAddress{index, 0});
  return it != entries_.end() && it->first.index == index;
}

SdoAbort LocalDictionary::lookup(ObjectAddress address, Entry*& out) noexcept {
  const auto it = entries_.find(address);
  if (it == entries_.end()) return has_index(address.index) ? SdoAbort::no_subindex : SdoAbort::no_object;
  out = &it->second;
  return SdoAbort::none;
}

SdoAbort LocalDictionary::check_download(ObjectAddress address, std::optional<std::size_t> size) noexcept {
  Entry* e = nullptr;
  if (const SdoAbort a = lookup(address, e); a != SdoAbort::none) return a;
  if (!writable(e->access)) return SdoAbort::read_only;
  if (!size) return SdoAbort::none;
  if (is_numeric(type_class(e->type))) {
    if (*size > size_of(e->type)) return SdoAbort::length_too_high;
    if (*size < size_of(e->type)) return SdoAbort::length_too_low;
  } else if (*size > e->capacity) {
    return SdoAbort::length_too_high;
  }
  return SdoAbort::none;
}

SdoAbort LocalDictionary::read(ObjectAddress address, std::span<std::uint8_t> out,
                               std::size_t& size) noexcept {
  Entry* e = nullptr;
  if (const SdoAbort a = lookup(address, e); a != SdoAbort::none) return a;
  if (!readable(e->access)) return SdoAbort::write_only;
  if (e->value.size() > out.size()) return SdoAbort::out_of_memory;
  std::copy(e->value.begin(), e->value.end(), out.begin());
  size = e->value.size();
  return SdoAbort::none;
}

SdoAbort LocalDictionary::write(ObjectAddress address, std::span<const std::uint8_t> data,
                                bool size_indicated) noexcept {
  Entry* e = nullptr;
  if (const SdoAbort a = lookup(address, e); a != SdoAbort::none) return a;
  if (!writable(e->access)) return SdoAbort::read_only;
  // An expedited download without a size carries 4 bytes: the object's own size decides.
  if (!size_indicated && is_numeric(type_class(e->type)) && data.size() > size_of(e->type))
    data = data.first(size_of(e->type));
  if (const SdoAbort a = check_value(*e, data); a != SdoAbort::none) return a;
  if (hook_) {
    if (const SdoAbort a = hook_(address, data); a != SdoAbort::none) return a;
  }
  e->value.assign(data.begin(), data.end());  // within the capacity reserved at add()
  return SdoAbort::none;
}

}  // namespace saw::canopen
