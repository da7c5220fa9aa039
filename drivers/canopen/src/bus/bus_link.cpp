#include "saw/canopen/bus_link.hpp"

#include <cstdint>
#include <cstdio>
#include <map>
#include <mutex>
#include <stdexcept>

#include "saw/can/borrowed_bus.hpp"

namespace saw::canopen {

namespace {

std::mutex registry_mutex;
std::map<std::string, std::weak_ptr<BusTask>>& bus_tasks() {
  static std::map<std::string, std::weak_ptr<BusTask>> m;
  return m;
}
std::map<std::string, std::string>& claims() {
  static std::map<std::string, std::string> c;
  return c;
}

}  // namespace

void publish_bus_task(const std::string& name, std::shared_ptr<BusTask> task) {
  const std::lock_guard lock(registry_mutex);
  if (auto old = bus_tasks()[name].lock(); old != nullptr)
    throw std::runtime_error("a CANopen bus named '" + name + "' exists in this process already");
  bus_tasks()[name] = task;
}

void withdraw_bus_task(const std::string& name) noexcept {
  const std::lock_guard lock(registry_mutex);
  bus_tasks().erase(name);
}

std::shared_ptr<BusTask> find_bus_task(const std::string& name) {
  const std::lock_guard lock(registry_mutex);
  const auto it = bus_tasks().find(name);
  std::shared_ptr<BusTask> t = it == bus_tasks().end() ? nullptr : it->second.lock();
  if (t == nullptr)
    throw std::runtime_error("bus '" + name +
                             "' is no canopen_bus component of this deployment (a canopen_bus named '" +
                             name + "' must come before the components on it)");
  return t;
}

BusClaim::BusClaim(std::string bus, const std::string& owner) : bus_(std::move(bus)) {
  const std::lock_guard lock(registry_mutex);
  const auto [it, fresh] = claims().emplace(bus_, owner);
  if (!fresh)
    throw std::runtime_error("CAN bus " + bus_ + " has a CANopen master in this process already ('" +
                             it->second + "'): put its components on one canopen_bus");
}

BusClaim::~BusClaim() {
  const std::lock_guard lock(registry_mutex);
  claims().erase(bus_);
}

bool is_bus_uri(const std::string& bus) noexcept {
  return bus.starts_with("virtual:") || bus.starts_with("socketcan:");
}

namespace {

std::string period_text(TimeNs ns) {
  char b[32];
  if (ns % 1'000'000 == 0)
    std::snprintf(b, sizeof b, "%lld ms", static_cast<long long>(ns / 1'000'000));
  else if (ns % 1'000 == 0)
    std::snprintf(b, sizeof b, "%lld us", static_cast<long long>(ns / 1'000));
  else
    std::snprintf(b, sizeof b, "%lld ns", static_cast<long long>(ns));
  return b;
}

void check_period(const std::string& bus, const std::string& client, TimeNs period, const BusTask& task) {
  // A slower client would miss SYNCs' TPDOs and leave SYNCs without its RPDOs, a faster one
  // would queue two setpoints for one SYNC: one period for the bus and its clients.
  if (period != task.config().period)
    throw std::runtime_error("'" + client + "' runs every " + period_text(period) + ", its bus task '" + bus +
                             "' every " + period_text(task.config().period) +
                             ": a client of a canopen_bus must have the bus task's period");
}

// An offset in the period.
std::string offset_text(TimeNs ns) {
  char b[32];
  if (ns % 1'000 == 0)
    std::snprintf(b, sizeof b, "%lld us", static_cast<long long>(ns / 1'000));
  else
    std::snprintf(b, sizeof b, "%lld ns", static_cast<long long>(ns));
  return b;
}

}  // namespace

TaskConfig client_task(const std::string& bus, const std::string& client, TaskConfig task) {
  if (is_bus_uri(bus)) return task;
  const std::shared_ptr<BusTask> t = find_bus_task(bus);
  check_period(bus, client, task.period.count(), *t);
  const BusTaskConfig& k = t->config();
  if (k.send_offset == 0) return task;  // no phases: the caller cycles the bus task
  if (task.offset.count() == 0) {
    task.offset = std::chrono::nanoseconds(k.route_offset + (k.send_offset - k.route_offset) / 2);
    return task;
  }
  if (task.offset.count() <= k.route_offset || task.offset.count() >= k.send_offset)
    throw std::runtime_error(
        "'" + client + "' runs at offset " + offset_text(task.offset.count()) +
        " in the period, its bus task '" + bus + "' routes the frames received at " +
        offset_text(k.route_offset) + " and sends SYNC at " + offset_text(k.send_offset) +
        ": a client of a canopen_bus runs between the two (an offset above " + offset_text(k.route_offset) +
        " and below " + offset_text(k.send_offset) + ", or none: the middle)");
  return task;
}

BusLink link_bus(const std::string& bus, const std::string& client, TimeNs period,
                 std::span<const std::uint8_t> nodes, std::span<const std::uint32_t> tpdos) {
  BusLink l;
  if (is_bus_uri(bus)) {
    can::BusConfig c;
    c.uri = bus;
    l.owned = can::open_bus(c);
    l.claim = std::make_unique<BusClaim>(bus, client);
    l.bus = l.owned.get();
    return l;
  }
  l.task = find_bus_task(bus);
  check_period(bus, client, period, *l.task);
  try {
    l.port = &l.task->attach(client, nodes, tpdos);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  l.bus = l.port;
  return l;
}

BusLink link_callers_bus(can::Bus& bus, const std::string& client) {
  BusLink l;
  l.claim = std::make_unique<BusClaim>(
      "'" + bus.name() + "' at " + std::to_string(reinterpret_cast<std::uintptr_t>(&bus)), client);
  l.owned = std::make_unique<can::BorrowedBus>(bus);
  l.bus = l.owned.get();
  return l;
}

}  // namespace saw::canopen
