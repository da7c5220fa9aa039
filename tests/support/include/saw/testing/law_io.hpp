// LawIo: one declared input and one declared output of a law, held by a test that steps the law
// by hand (a passivity port's energy or wave in, the value the law sends back out).
#pragma once

#include "saw/teleop/law.hpp"
#include "saw/type_info.hpp"

namespace saw::testing {

template <Plain In, Plain Out>
struct LawIo {
  In value{};         // the input's last valid value
  bool valid = true;  // false: none yet (nullptr to the law)
  bool fresh = true;  // read with this cycle's row
  Out sent_value{};   // what the law set
  teleop::DeclaredValue input{type_info_of<In>(), nullptr, false};
  teleop::OutputValue output{type_info_of<Out>(), &sent_value, false};

  // Points `in` at this cycle's input and an output not set yet. LawIo must outlive the step.
  teleop::LawInputs& attach(teleop::LawInputs& in) {
    input.value = valid ? &value : nullptr;
    input.fresh = fresh;
    output.set = false;
    in.declared = teleop::DeclaredInputs(&input, 1);
    in.outputs = teleop::DeclaredOutputs(&output, 1);
    return in;
  }
  // What the law sent this cycle, or nullptr.
  const Out* sent() const { return output.set ? &sent_value : nullptr; }
};

}  // namespace saw::testing
