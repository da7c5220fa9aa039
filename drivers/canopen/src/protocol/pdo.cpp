#include "saw/canopen/pdo.hpp"

#include <stdexcept>
#include <string>

#include "saw/canopen/cob.hpp"

namespace saw::canopen {

std::string_view to_string(PdoKind k) noexcept { return k == PdoKind::rpdo ? "RPDO" : "TPDO"; }

std::string_view to_string(PdoReceive r) noexcept {
  switch (r) {
    case PdoReceive::ok:
      return "ok";
    case PdoReceive::other_identifier:
      return "another identifier";
    case PdoReceive::not_data:
      return "not a classic data frame";
    case PdoReceive::wrong_length:
      return "length does not match the mapping";
  }
  return "unknown";
}

namespace {

DataType unsigned_of_width(std::uint8_t bits) noexcept {
  if (bits <= 1) return DataType::boolean;
  if (bits <= 8) return DataType::unsigned8;
  if (bits <= 16) return DataType::unsigned16;
  if (bits <= 24) return DataType::unsigned24;
  if (bits <= 32) return DataType::unsigned32;
  if (bits <= 40) return DataType::unsigned40;
  if (bits <= 48) return DataType::unsigned48;
  if (bits <= 56) return DataType::unsigned56;
  return DataType::unsigned64;
}

std::string name(const PdoMapping& m) { return std::string(to_string(m.kind)) + std::to_string(m.number); }

std::uint64_t mask_of(unsigned bits) noexcept {
  return bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
}

}  // namespace

PdoEntry PdoEntry::from_u32(std::uint32_t v, std::optional<DataType> type) noexcept {
  PdoEntry e;
  e.address = {static_cast<std::uint16_t>(v >> 16), static_cast<std::uint8_t>(v >> 8)};
  e.bits = static_cast<std::uint8_t>(v);
  if (type) {
    e.type = *type;
  } else if (const auto t = data_type_from_code(e.address.index); e.dummy() && t) {
    e.type = *t;
  } else {
    e.type = unsigned_of_width(e.bits);
  }
  return e;
}

PdoMapping& PdoMapping::map(const PdoEntry& e) {
  if (count >= max_pdo_entries)
    throw std::invalid_argument(name(*this) + ": more than " + std::to_string(max_pdo_entries) + " entries");
  entries[count++] = e;
  return *this;
}

PdoMapping& PdoMapping::map(ObjectAddress a, DataType t) { return map(PdoEntry::of(a, t)); }

std::size_t PdoMapping::bits() const noexcept {
  std::size_t b = 0;
  for (std::size_t i = 0; i < count && i < max_pdo_entries; ++i) b += entries[i].bits;
  return b;
}

std::uint32_t default_pdo_cob_id(PdoKind kind, std::uint16_t number, std::uint8_t node) noexcept {
  if (number < 1 || number > 4) return pdo_invalid;
  const std::uint32_t base = kind == PdoKind::tpdo ? cob::tpdo1 : cob::rpdo1;
  return base + 0x100u * (number - 1u) + node;
}

void check(const PdoMapping& m) {
  const auto fail = [&](const std::string& what) { throw std::invalid_argument(name(m) + ": " + what); };
  if (m.number < 1 || m.number > 512) fail("number must be 1..512");
  if (!m.enabled) return;
  if (m.cob_id > CAN_SFF_MASK) fail("COB-ID " + std::to_string(m.cob_id) + " is not an 11-bit identifier");
  // CiA 301 7.3.5's restricted identifiers, and SYNC's 0x080 (a PDO there would be taken for SYNC).
  const std::uint32_t id = m.cob_id;
  if (id <= 0x080 || (id >= 0x101 && id <= 0x180) || (id >= 0x581 && id <= 0x5FF) ||
      (id >= 0x601 && id <= 0x67F) || (id >= 0x6E0 && id <= 0x6FF) || id >= 0x701)
    fail("COB-ID " + std::to_string(id) + " is reserved by CiA 301");
  if (m.count == 0) fail("no entry mapped");
  if (m.bits() > 64) fail(std::to_string(m.bits()) + " bits mapped, a classic PDO holds 64");
  for (std::size_t i = 0; i < m.count; ++i) {
    const PdoEntry& e = m.entries[i];
    const std::string where = "entry " + std::to_string(i + 1) + " (" + to_string(e.address) + ")";
    if (e.bits == 0) fail(where + ": 0 bits");
    if (!is_numeric(type_class(e.type)))
      fail(where + ": " + std::string(to_string(e.type)) + " cannot be mapped");
    const std::size_t width = 8 * size_of(e.type);
    const bool ok = e.bits == width || (e.type == DataType::boolean && e.bits == 1);
    if (!ok)
      fail(where + ": " + std::to_string(e.bits) + " bits mapped, " + std::string(to_string(e.type)) +
           " has " + std::to_string(width));
  }
}

std::vector<SdoWrite> configuration_writes(const PdoMapping& m) {
  check(m);
  const std::uint16_t comm = m.communication_index(), map = m.mapping_index();
  std::vector<SdoWrite> w;
  // A disabled PDO keeps its identifier under bit 31: a device may refuse a write that changes
  // the identifier bits of a PDO that is still valid (CiA 301 7.5.2.35).
  const std::uint32_t cob_id = m.cob_id & CAN_SFF_MASK;
  w.push_back({{comm, 1}, DataType::unsigned32, cob_id | pdo_invalid});
  if (!m.enabled) return w;
  w.push_back({{map, 0}, DataType::unsigned8, 0});
  for (std::uint8_t i = 0; i < m.count; ++i)
    w.push_back({{map, static_cast<std::uint8_t>(i + 1)}, DataType::unsigned32, m.entries[i].to_u32()});
  w.push_back({{map, 0}, DataType::unsigned8, m.count});
  w.push_back({{comm, 2}, DataType::unsigned8, m.transmission});
  if (m.inhibit_time != 0 && m.kind == PdoKind::tpdo)
    w.push_back({{comm, 3}, DataType::unsigned16, m.inhibit_time});
  if (m.event_timer != 0) w.push_back({{comm, 5}, DataType::unsigned16, m.event_timer});
  w.push_back({{comm, 1}, DataType::unsigned32, cob_id});
  return w;
}

PdoLayout::PdoLayout(const PdoMapping& m) {
  check(m);
  if (!m.enabled) throw std::invalid_argument(name(m) + ": a disabled PDO has no layout");
  cob_id_ = m.cob_id;
  count_ = m.count;
  bytes_ = static_cast<std::uint8_t>(m.bytes());
  std::uint8_t offset = 0;
  for (std::size_t i = 0; i < m.count; ++i) {
    slots_[i] = {offset, m.entries[i].bits, m.entries[i].type};
    offset = static_cast<std::uint8_t>(offset + m.entries[i].bits);
  }
}

PdoPacker::PdoPacker(const PdoLayout& layout) noexcept : layout_(layout) {
  frame_.id = layout.cob_id();
  frame_.len = layout.bytes();
}

Codec PdoPacker::set_number(std::size_t slot, const Number& value) noexcept {
  if (slot >= layout_.size()) return Codec::invalid;
  const PdoSlot& s = layout_.slot(slot);
  std::uint8_t bytes[8] = {};
  if (const Codec c = encode(s.type, value, bytes); c != Codec::ok) return c;
  std::uint64_t raw = 0;
  for (std::size_t i = 0; i < size_of(s.type); ++i) raw |= static_cast<std::uint64_t>(bytes[i]) << (8 * i);
  // The payload as one little-endian word: PDO bits fill from bit 0 of byte 0 upward.
  std::uint64_t word = 0;
  for (std::size_t i = 0; i < 8; ++i) word |= static_cast<std::uint64_t>(frame_.data[i]) << (8 * i);
  const std::uint64_t mask = mask_of(s.bits) << s.offset;
  word = (word & ~mask) | ((raw << s.offset) & mask);
  for (std::size_t i = 0; i < 8; ++i) frame_.data[i] = static_cast<std::uint8_t>(word >> (8 * i));
  return Codec::ok;
}

PdoReceive PdoUnpacker::receive(const can::Frame& f) noexcept {
  if (f.can_id() != layout_.cob_id()) return PdoReceive::other_identifier;
  if (!canopen_data_frame(f)) return PdoReceive::not_data;
  if (f.len != layout_.bytes()) return PdoReceive::wrong_length;
  std::uint64_t word = 0;
  for (std::size_t i = 0; i < f.len; ++i) word |= static_cast<std::uint64_t>(f.data[i]) << (8 * i);
  word_ = word;
  received_ = true;
  return PdoReceive::ok;
}

Codec PdoUnpacker::get_number(std::size_t slot, Number& out) const noexcept {
  if (slot >= layout_.size() || !received_) return Codec::invalid;
  const PdoSlot& s = layout_.slot(slot);
  const std::uint64_t raw = (word_ >> s.offset) & mask_of(s.bits);
  std::uint8_t bytes[8] = {};
  for (std::size_t i = 0; i < size_of(s.type); ++i) bytes[i] = static_cast<std::uint8_t>(raw >> (8 * i));
  return decode(s.type, {bytes, size_of(s.type)}, out);
}

MappedAt find_mapped(std::span<const PdoMapping> pdos, PdoKind kind, ObjectAddress object) noexcept {
  int n = 0;
  for (const PdoMapping& m : pdos) {
    if (!m.enabled || m.kind != kind) continue;
    for (std::size_t s = 0; s < m.count; ++s)
      if (m.entries[s].address == object) return {n, static_cast<int>(s)};
    ++n;
  }
  return {};
}

}  // namespace saw::canopen
