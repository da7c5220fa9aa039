// The conformance suite on canopen_io, a client of a shared bus task, against the simulated
// CiA 401 I/O node (canopen_io_rig.hpp). Its contract holds (SafeState::hold): a refused command
// or commands that stop keep the outputs where they are; disable, pause, a fault and a stop send
// each channel's safe value.
#include "canopen_io_rig.hpp"

namespace saw::conformance {
namespace {

INSTANTIATE_TEST_SUITE_P(CanopenIo, DeviceConformance,
                         testing::Values(Driver{"canopen_io_on_a_bus_task",
                                                [] { return std::make_unique<CanopenIoRig>(); }}),
                         driver_name);

}  // namespace
}  // namespace saw::conformance
