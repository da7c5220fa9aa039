// PassivityController: time-domain passivity at one port of a teleoperation network — the energy
// observed and what would be created dissipated.
#pragma once

#include <Eigen/Core>
#include <limits>

namespace saw::teleop {

// Energy through one port of a network, from the force the network applies to the device and the
// device's velocity: output while the network does work on the device (F·v > 0), input while the
// device does work on the network. Both only grow.
struct PortEnergy {
  double in = 0;   // J
  double out = 0;  // J
};

// The passivity observer and controller of an impedance port (velocity in, force out) of a
// two-port network whose other port is far away (Hannaford & Ryu 2002; Ryu, Kwon & Hannaford
// 2004). The network is passive when no port ever gives out more energy than has come in at the
// other: for each direction, E_out(here, t) ≤ E_in(there, t − T), where the remote input arrives
// over the same link as the data, T late. Each step, the force the law wants is applied unless
// its output this step would break that bound; then a damping α·v is subtracted, just enough
// to keep it. The damping force never exceeds the law force's own component along the motion
// (α·|v|² ≤ F·v), so it needs no cap to stay bounded; `max_damping` caps α where a device must not
// be given more (the bound may then be broken, and margin() says by how much). Since the remote input
// arrives late, a delayed channel has less energy to spend the longer the delay: transparency
// degrades with delay, stability does not.
class PassivityController {
 public:
  explicit PassivityController(double max_damping = std::numeric_limits<double>::infinity()) noexcept
      : max_damping_(max_damping) {}

  struct Step {
    Eigen::Vector3d force;  // to apply
    double damping = 0;     // α this step, N·s/m
  };
  // `remote_in`: the other port's input energy as last received (J). No allocation, no throw.
  Step step(const Eigen::Vector3d& force, const Eigen::Vector3d& velocity, double remote_in,
            double dt) noexcept;

  const PortEnergy& energy() const noexcept { return energy_; }
  // Energy the controller took out (J) and the observed margin after the last step (J; negative
  // only when the damping cap kept it from restoring passivity).
  double dissipated() const noexcept { return dissipated_; }
  double margin() const noexcept { return margin_; }
  double last_damping() const noexcept { return damping_; }  // α of the last step, N·s/m
  void reset() noexcept { *this = PassivityController(max_damping_); }
  // 0: observe only (the force is never changed, the figures still kept).
  void set_max_damping(double d) noexcept { max_damping_ = d; }

 private:
  double max_damping_;
  PortEnergy energy_;
  double dissipated_ = 0, margin_ = 0, damping_ = 0;
};

}  // namespace saw::teleop
