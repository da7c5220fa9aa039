// ServedDevice: a 1 kHz task exported through the bridge and mapped to DDS by a gateway, all in
// this process, on a DDS domain it holds alone (tests side by side do not see each other).
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "saw/bridge/exporter.hpp"
#include "saw/fault.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/manager.hpp"
#include "saw/testing/dds_domain.hpp"
#include "saw/testing/unique_name.hpp"

namespace saw::testing {

// Provided "arm": count (read), add (write, limited to ±10,000,000), tripled (qualified read),
// ticked (event, every 10th cycle), trip (void: raises `fault`, a FaultInfo event, as a drive's
// emergency would), clear (void: `fault` with code none, as a re-enabled component says it).
class CountingDevice : public Task {
 public:
  explicit CountingDevice(std::string name)
      : Task(std::move(name), TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& p = provide("arm");
    p.add_command_read("count", state_table().add_column("count", &count_));
    p.add_command_write<std::int64_t>("add", [this](const std::int64_t& v) { count_ += v; });
    p.limit("add", -10'000'000, 10'000'000);
    p.add_command_qualified_read<std::int64_t, std::int64_t>(
        "tripled", [](const std::int64_t& q, std::int64_t& r) { r = 3 * q; });
    ticked_ = &p.add_event_write<std::int64_t>("ticked");
    fault_ = &p.add_event_write<FaultInfo>("fault");
    p.add_command_void("trip", [this] {
      FaultInfo f;
      f.code = FaultCode::device_error;
      f.set_source("node 5");
      f.detail = 0x2310;
      (void)(*fault_)(f);
    });
    p.add_command_void("clear", [this] { (void)(*fault_)(FaultInfo{}); });  // re-enabled: code none
  }
  void run() override {
    ++count_;
    if (count_ % 10 == 0) (void)(*ticked_)(count_);
  }

 private:
  std::int64_t count_ = 0;
  EventWrite<std::int64_t>* ticked_;
  EventWrite<FaultInfo>* fault_;
};

struct ServedDevice {
  explicit ServedDevice(const std::string& prefix, double display_rate = gateway::default_display_rate)
      : name(unique_name(prefix)), domain(claim.id()), device(name), exporter(device, "arm") {
    manager.add(device);
    manager.start();
    gateway::GatewayConfig config;
    config.attach = {name};
    config.dds.domain = domain;
    config.display_rate = display_rate;
    served = std::make_unique<gateway::Gateway>(config);
  }
  ~ServedDevice() {
    served.reset();
    manager.stop();  // (stopping twice is allowed)
  }
  std::string name;
  DdsDomain claim;  // held while the device is served
  int domain;
  CountingDevice device;
  bridge::Exporter exporter;
  Manager manager;
  std::unique_ptr<gateway::Gateway> served;
};

// A participant of ours on `domain` (loopback only), for the tests' own DDS entities.
inline eprosima::fastdds::dds::DomainParticipant* test_participant(int domain, const char* name) {
  gateway::ParticipantConfig pc;
  pc.domain = domain;
  pc.name = name;
  return gateway::make_participant(pc);
}

}  // namespace saw::testing
