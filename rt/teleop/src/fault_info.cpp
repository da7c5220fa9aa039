#include "saw/teleop/fault_info.hpp"

namespace saw::teleop {

FaultInfo fault_on(FaultSide side, FaultCode code, Status last_read, TimeNs age_ns) noexcept {
  FaultInfo f;
  f.code = code;
  f.last_read = last_read;
  f.age_ns = age_ns;
  f.set_source(to_string(side));
  return f;
}

}  // namespace saw::teleop
