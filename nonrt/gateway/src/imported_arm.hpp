// ImportedArm: a foreign CRTK arm on DDS (a dVRK master) presented as a local provided interface (internal).
#pragma once

#include <string>
#include <vector>

#include "dds_context.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/task.hpp"

namespace saw::gateway {

// Provided "arm" (crtk_arm.hpp), read-only (as the paper's research API was): measured_cp,
// measured_cv, measured_js, operating_state (reads); operating_state, clutch, operator_present
// (events).
// A 1 ms task of normal priority takes the newest samples; its state row is stamped with the
// arrival of the newest measured_cp, so a client sees the stream age when it stops. Samples that
// are not valid values (NaN, bad quaternion) are counted and dropped.
class ImportedArm : public Task {
 public:
  ImportedArm(DdsContext& dds, const ImportConfig& config);
  void run() override;
  std::uint64_t samples() const noexcept { return samples_.load(std::memory_order_relaxed); }
  std::uint64_t rejected() const noexcept { return rejected_.load(std::memory_order_relaxed); }
  // For the manifest: each imported value, its kind "import", and the topic it comes from.
  const std::vector<EndpointInfo>& endpoints() const noexcept { return endpoints_; }

 private:
  fdds::DataReader* reader(const std::string& name, const std::string& topic, const Mapping& m, Flow f);
  template <class M>
  fdds::DataReader* reader(M member, const std::string& topic, Flow f);
  template <class T>
  bool take_newest(fdds::DataReader* r, T& out);

  DdsContext& dds_;
  fdds::DataReader *cp_ = nullptr, *cv_ = nullptr, *js_ = nullptr, *state_ = nullptr, *clutch_ = nullptr,
                   *operator_ = nullptr;
  Pose measured_cp_;
  Twist measured_cv_;
  JointState measured_js_;
  OperatingState operating_state_;
  TimeNs cp_arrival_ = 0;
  EventWrite<OperatingState>* state_event_ = nullptr;
  EventWrite<ButtonEvent>*clutch_event_ = nullptr, *operator_event_ = nullptr;
  std::atomic<std::uint64_t> samples_{0}, rejected_{0};
  std::vector<EndpointInfo> endpoints_;
};

}  // namespace saw::gateway
