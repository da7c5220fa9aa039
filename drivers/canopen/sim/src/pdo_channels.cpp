#include "pdo_channels.hpp"

#include <cstring>
#include <exception>

#include "saw/canopen/cob.hpp"

namespace saw::canopen::sim {

namespace {

constexpr std::uint32_t cob_invalid = 0x80000000;   // bit 31: the PDO does not exist
constexpr std::uint32_t cob_extended = 0x20000000;  // bit 29: a 29-bit identifier
constexpr std::uint32_t cob_id_mask = 0x7FF;

struct Indices {
  PdoKind kind;
  std::uint16_t number;  // 1-based
  bool mapping;          // 0x16xx/0x1Axx rather than 0x14xx/0x18xx
};

std::optional<Indices> classify(std::uint16_t index) noexcept {
  const auto in = [&](std::uint16_t base) { return index >= base && index < base + PdoChannels::max_pdos; };
  if (in(0x1400)) return Indices{PdoKind::rpdo, static_cast<std::uint16_t>(index - 0x1400 + 1), false};
  if (in(0x1600)) return Indices{PdoKind::rpdo, static_cast<std::uint16_t>(index - 0x1600 + 1), true};
  if (in(0x1800)) return Indices{PdoKind::tpdo, static_cast<std::uint16_t>(index - 0x1800 + 1), false};
  if (in(0x1A00)) return Indices{PdoKind::tpdo, static_cast<std::uint16_t>(index - 0x1A00 + 1), true};
  return std::nullopt;
}

std::uint16_t communication_index(PdoKind k, std::uint16_t number) noexcept {
  return static_cast<std::uint16_t>((k == PdoKind::rpdo ? 0x1400 : 0x1800) + number - 1);
}
std::uint16_t mapping_index(PdoKind k, std::uint16_t number) noexcept {
  return static_cast<std::uint16_t>((k == PdoKind::rpdo ? 0x1600 : 0x1A00) + number - 1);
}

// CiA 301 7.3.5's identifiers a PDO may not use (and SYNC's), as pdo.cpp's check() refuses them.
bool restricted(std::uint32_t id) noexcept {
  return id <= 0x080 || (id >= 0x101 && id <= 0x180) || (id >= 0x581 && id <= 0x5FF) ||
         (id >= 0x601 && id <= 0x67F) || (id >= 0x6E0 && id <= 0x6FF) || id >= 0x701;
}

// 241..251 are reserved; 252 and 253 (on remote request) are TPDO types this drive does not do.
bool valid_transmission(std::uint64_t t) noexcept { return t <= 240 || t == 254 || t == 255; }

}  // namespace

Codec set_number(LocalDictionary& d, ObjectAddress a, const Number& n) noexcept {
  if (const auto* i = std::get_if<std::int64_t>(&n)) return d.set(a, *i);
  if (const auto* u = std::get_if<std::uint64_t>(&n)) return d.set(a, *u);
  return d.set(a, std::get<double>(n));
}

Codec get_number(const Entry& e, Number& out) noexcept {
  if (!is_numeric(type_class(e.type))) return Codec::invalid;
  return decode(e.type, std::span<const std::uint8_t>(e.value), out);
}

bool PdoChannels::is_pdo_parameter(std::uint16_t index) noexcept { return classify(index).has_value(); }

std::uint32_t PdoChannels::u32(ObjectAddress a, std::uint32_t fallback) const noexcept {
  std::uint32_t v = 0;
  return dictionary_.get(a, v) == Codec::ok ? v : fallback;
}

bool PdoChannels::rpdo_enabled(std::uint16_t number) const noexcept {
  return number >= 1 && number <= max_pdos && rpdos_[number - 1].enabled;
}
bool PdoChannels::tpdo_enabled(std::uint16_t number) const noexcept {
  return number >= 1 && number <= max_pdos && tpdos_[number - 1].enabled;
}

SdoAbort PdoChannels::check_entry(PdoKind kind, std::uint32_t value) const noexcept {
  if (value == 0) return SdoAbort::none;  // an empty slot
  const PdoEntry entry = PdoEntry::from_u32(value);
  if (entry.dummy()) {
    // Dummy entries fill bits of a received PDO; a transmitted one has nothing to fill them with.
    const auto type = data_type_from_code(entry.address.index);
    if (kind != PdoKind::rpdo || !type || !is_numeric(type_class(*type)) || entry.bits != 8 * size_of(*type))
      return SdoAbort::not_mappable;
    return SdoAbort::none;
  }
  const Entry* e = dictionary_.find(entry.address);
  if (e == nullptr)
    return dictionary_.has_index(entry.address.index) ? SdoAbort::no_subindex : SdoAbort::no_object;
  const bool access = kind == PdoKind::rpdo ? writable(e->access) : readable(e->access);
  if (!e->pdo_mappable || !access || !is_numeric(type_class(e->type))) return SdoAbort::not_mappable;
  const bool width = entry.bits == 8 * size_of(e->type) || (e->type == DataType::boolean && entry.bits == 1);
  return width ? SdoAbort::none : SdoAbort::not_mappable;
}

SdoAbort PdoChannels::check_write(ObjectAddress address, std::uint64_t value) const noexcept {
  const auto which = classify(address.index);
  if (!which) return SdoAbort::none;
  const std::uint16_t comm = communication_index(which->kind, which->number);
  const std::uint16_t map = mapping_index(which->kind, which->number);
  const std::uint32_t cob = u32({comm, 1}, cob_invalid);
  const bool valid = (cob & cob_invalid) == 0;
  if (!which->mapping) {
    switch (address.subindex) {
      case 1: {
        const auto v = static_cast<std::uint32_t>(value);
        if ((v & cob_extended) != 0) return SdoAbort::invalid_value;  // no 29-bit PDOs here
        const bool becomes_valid = (v & cob_invalid) == 0;
        // CiA 301: the identifier of an existing PDO cannot change; invalidate it first.
        if (valid && becomes_valid && ((v ^ cob) & cob_id_mask) != 0) return SdoAbort::invalid_value;
        if (becomes_valid && restricted(v & cob_id_mask)) return SdoAbort::invalid_value;
        return SdoAbort::none;
      }
      case 2:
        return valid_transmission(value) ? SdoAbort::none : SdoAbort::invalid_value;
      default:
        return SdoAbort::none;
    }
  }
  // Mapping parameter: only while the PDO does not exist, and entries only while sub 0 is 0
  // (CiA 301 7.5.2.36's procedure; CANopenNode answers both with "unsupported access").
  if (valid) return SdoAbort::unsupported_access;
  if (address.subindex == 0) {
    if (value > max_pdo_entries) return SdoAbort::pdo_too_long;
    std::size_t bits = 0;
    for (std::uint8_t i = 1; i <= value; ++i) {
      const std::uint32_t entry = u32({map, i}, 0);
      if (entry == 0) return SdoAbort::not_mappable;
      if (const SdoAbort a = check_entry(which->kind, entry); a != SdoAbort::none) return a;
      bits += entry & 0xFF;
    }
    return bits > 64 ? SdoAbort::pdo_too_long : SdoAbort::none;
  }
  std::uint8_t count = 0;
  if (dictionary_.get({map, 0}, count) == Codec::ok && count != 0) return SdoAbort::unsupported_access;
  return check_entry(which->kind, static_cast<std::uint32_t>(value));
}

std::optional<PdoMapping> PdoChannels::mapping(PdoKind kind, std::uint16_t number) const noexcept {
  const std::uint16_t comm = communication_index(kind, number);
  const std::uint16_t map = mapping_index(kind, number);
  std::uint32_t cob = 0;
  if (dictionary_.get({comm, 1}, cob) != Codec::ok) return std::nullopt;
  PdoMapping m;
  m.kind = kind;
  m.number = number;
  m.cob_id = cob & cob_id_mask;
  m.enabled = (cob & (cob_invalid | cob_extended)) == 0;
  std::uint8_t transmission = transmission::event_profile;
  (void)dictionary_.get({comm, 2}, transmission);
  m.transmission = transmission;
  std::uint16_t v16 = 0;
  if (kind == PdoKind::tpdo && dictionary_.get({comm, 3}, v16) == Codec::ok) m.inhibit_time = v16;
  if (dictionary_.get({comm, 5}, v16) == Codec::ok) m.event_timer = v16;
  std::uint8_t count = 0;
  (void)dictionary_.get({map, 0}, count);
  for (std::uint8_t i = 1; i <= count && i <= max_pdo_entries; ++i) {
    const PdoEntry raw = PdoEntry::from_u32(u32({map, i}, 0));
    const Entry* e = raw.dummy() ? nullptr : dictionary_.find(raw.address);
    m.entries[m.count++] = e != nullptr ? PdoEntry::from_u32(raw.to_u32(), e->type) : raw;
  }
  return m;
}

void PdoChannels::rebuild(PdoKind kind, std::uint16_t number) noexcept {
  const std::size_t slot = number - 1u;
  if (kind == PdoKind::rpdo) {
    rpdos_[slot] = Rpdo{};
  } else {
    tpdos_[slot] = Tpdo{};
  }
  const auto m = mapping(kind, number);
  if (!m || !m->enabled || m->count == 0) return;  // a valid PDO with nothing mapped carries nothing
  try {
    const PdoLayout layout(*m);  // check(): the same rules the master's side applies
    if (kind == PdoKind::rpdo) {
      Rpdo& r = rpdos_[slot];
      r.unpacker.emplace(layout);
      for (std::size_t i = 0; i < m->count; ++i) r.objects[i] = m->entries[i].address;
      r.synchronous = m->transmission <= 240;
      r.deadline = static_cast<TimeNs>(m->event_timer) * 1'000'000;
      r.enabled = true;
    } else {
      Tpdo& t = tpdos_[slot];
      for (std::size_t i = 0; i < m->count; ++i) {
        t.sources[i] = dictionary_.find(m->entries[i].address);
        if (t.sources[i] == nullptr) {  // a TPDO has no dummy entries: every one must be there
          ++invalid_;
          t = Tpdo{};
          return;
        }
      }
      t.packer.emplace(layout);
      t.transmission = m->transmission;
      t.inhibit = static_cast<TimeNs>(m->inhibit_time) * 100'000;
      t.event_timer = static_cast<TimeNs>(m->event_timer) * 1'000'000;
      t.enabled = true;
    }
  } catch (const std::exception&) {
    // An EDS's own mapping that check() refuses (writes by SDO were checked before storing).
    ++invalid_;
    if (kind == PdoKind::rpdo) {
      rpdos_[slot] = Rpdo{};
    } else {
      tpdos_[slot] = Tpdo{};
    }
  }
}

void PdoChannels::written(ObjectAddress address) noexcept {
  if (const auto which = classify(address.index)) rebuild(which->kind, which->number);
}

void PdoChannels::rebuild_all() noexcept {
  for (std::uint16_t n = 1; n <= max_pdos; ++n) {
    rebuild(PdoKind::rpdo, n);
    rebuild(PdoKind::tpdo, n);
  }
}

void PdoChannels::start(TimeNs now) noexcept {
  for (Tpdo& t : tpdos_) {
    if (!t.enabled) continue;
    t.syncs = 0;
    t.sent = false;
    t.last_sent = now;
    t.due = t.transmission >= transmission::event_manufacturer;
  }
  for (Rpdo& r : rpdos_) {
    r.pending = r.fresh = r.expired = false;
    r.seen.reset();  // the deadline is watched from the first RPDO in operational
  }
}

std::uint16_t PdoChannels::expired_rpdo(TimeNs now) noexcept {
  for (std::uint16_t n = 1; n <= max_pdos; ++n) {
    Rpdo& r = rpdos_[n - 1u];
    if (r.fresh) {
      r.fresh = r.expired = false;
      r.seen = now;
    }
    if (!r.enabled || r.deadline == 0 || !r.seen || r.expired || now - *r.seen <= r.deadline) continue;
    r.expired = true;
    return n;
  }
  return 0;
}

void PdoChannels::apply(Rpdo& r) noexcept {
  for (std::size_t i = 0; i < r.unpacker->layout().size(); ++i) {
    if (r.objects[i].index < 0x20) continue;  // a dummy entry
    Number n;
    if (r.unpacker->get_number(i, n) != Codec::ok || set_number(dictionary_, r.objects[i], n) != Codec::ok)
      ++refused_values_;  // e.g. a target torque beyond 0x6071's limits: that value is not taken
  }
}

PdoChannels::Receive PdoChannels::on_frame(const can::Frame& f) noexcept {
  for (Rpdo& r : rpdos_) {
    if (!r.enabled) continue;
    switch (r.unpacker->receive(f)) {
      case PdoReceive::other_identifier:
        continue;
      case PdoReceive::not_data:
        return Receive::refused;
      case PdoReceive::wrong_length:
        return Receive::wrong_length;
      case PdoReceive::ok:
        r.fresh = true;
        if (r.synchronous) {
          r.pending = true;
          return Receive::latched;
        }
        apply(r);
        return Receive::applied;
    }
  }
  return Receive::not_rpdo;
}

bool PdoChannels::pack(Tpdo& t) noexcept {
  for (std::size_t i = 0; i < t.packer->layout().size(); ++i) {
    Number n;
    if (get_number(*t.sources[i], n) == Codec::ok) (void)t.packer->set_number(i, n);
  }
  const can::Frame& f = t.packer->frame();
  return !t.sent || std::memcmp(f.data, t.last_frame.data, f.len) != 0;
}

void PdoChannels::on_sync(TimeNs) noexcept {
  for (Rpdo& r : rpdos_) {
    if (r.enabled && r.pending) {
      apply(r);
      r.pending = false;
    }
  }
  for (Tpdo& t : tpdos_) {
    if (!t.enabled || t.transmission > 240) continue;
    const bool changed = pack(t);
    if (t.transmission == transmission::synchronous_acyclic) {
      t.due = t.due || changed;
    } else if (++t.syncs >= t.transmission) {
      t.syncs = 0;
      t.due = true;
    }
  }
}

std::optional<can::Frame> PdoChannels::poll(TimeNs now) noexcept {
  for (Tpdo& t : tpdos_) {
    if (!t.enabled) continue;
    if (t.transmission >= transmission::event_manufacturer) {
      const bool changed = pack(t);
      const bool inhibited = t.sent && now - t.last_sent < t.inhibit;
      if (!inhibited && (changed || t.due || (t.event_timer > 0 && now - t.last_sent >= t.event_timer)))
        t.due = true;
      if (inhibited) continue;
    }
    if (!t.due) continue;
    t.due = false;
    t.sent = true;
    t.last_sent = now;
    t.last_frame = t.packer->frame();
    return t.last_frame;
  }
  return std::nullopt;
}

}  // namespace saw::canopen::sim
