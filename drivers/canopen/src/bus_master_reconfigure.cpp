// BusMaster's re-configuration of a drive that rebooted, from the cycle: RT code.
#include "bus_master_impl.hpp"

namespace saw::canopen {

void BusMaster::reconfigure(std::size_t i, TimeNs now) noexcept {
  Axis& a = impl_->axes[i];
  a.reconfig = {};
  a.reconfig.state = Reconfiguration::State::busy;
  a.reconfig_next = 0;
  a.reconfig_started = a.reconfig_starting = false;
  a.reconfig_since = now;
  a.tpdo_seen = 0;  // its TPDOs, once it sends them again, decide
  a.feedback.valid = false;
}

const Reconfiguration& BusMaster::reconfiguration(std::size_t i) const noexcept {
  return impl_->axes[i].reconfig;
}

void BusMaster::Impl::step_reconfiguration(Axis& a, TimeNs now) noexcept {
  if (a.reconfig.state != Reconfiguration::State::busy) return;
  const auto index = static_cast<int>(&a - axes.data());
  if (a.reconfig_starting) {
    if (a.health.nmt_state == NmtState::operational) {
      a.reconfig.state = Reconfiguration::State::done;
      a.feedback.watch_from = now;
    } else if (now - a.reconfig_since > 2'000'000'000) {
      a.reconfig.state = Reconfiguration::State::failed;  // no operational heartbeat within 2 s
    }
    return;
  }
  if (sdo_axis == index) return;  // a runtime transfer on its channel: next cycle
  if (a.reconfig_started && !a.sdo.busy()) {
    const EncodedWrite& w = a.writes[a.reconfig_next];
    const SdoResult& r = a.sdo.result();
    const bool missing = r.abort == SdoAbort::no_object || r.abort == SdoAbort::no_subindex;
    if (r.status != SdoStatus::done && !(w.optional && missing)) {
      a.reconfig.state = Reconfiguration::State::failed;
      a.reconfig.object = w.address;
      a.reconfig.abort = r.abort;
      return;
    }
    ++a.reconfig_next;
    a.reconfig_started = false;
  }
  if (!a.reconfig_started && a.reconfig_next < a.writes.size()) {
    const EncodedWrite& w = a.writes[a.reconfig_next];
    a.reconfig_started = a.sdo.download(w.address, std::span(w.bytes.data(), w.size), now);
  }
  while (const auto f = a.sdo.poll(now)) out(*f);
  if (!a.reconfig_started && a.reconfig_next >= a.writes.size()) {
    out(nmt_frame(NmtCommand::start, a.config.node));
    a.reconfig_starting = true;
    a.reconfig_since = now;
  }
}

}  // namespace saw::canopen
