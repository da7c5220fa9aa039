// The built-in control laws: one line each.
#include "saw/deploy/registry.hpp"
#include "saw/teleop/law_registry.hpp"
#include "saw/teleop/laws/collaborative.hpp"
#include "saw/teleop/laws/passive_bilateral.hpp"
#include "saw/teleop/laws/position_position.hpp"
#include "saw/teleop/laws/surgical.hpp"
#include "saw/teleop/laws/wave_variables.hpp"

namespace saw::teleop {

LawRegistry& laws(deploy::ComponentRegistry& registry) { return registry.extension<LawRegistry>(); }

void add_builtin_laws(LawRegistry& r) {
  r.add<CollaborativeLaw>();
  r.add<PositionPositionLaw>();
  r.add<PassiveBilateralLaw>();
  r.add<WaveVariableLaw>();
  r.add<SurgicalLaw>();
}

}  // namespace saw::teleop
