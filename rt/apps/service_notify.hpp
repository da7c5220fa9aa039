// A service manager's readiness protocol (sd_notify's datagram to $NOTIFY_SOCKET), without libsystemd.
#pragma once

#include <string_view>

namespace saw::apps {

// Sends `state` ("READY=1", "STOPPING=1", "STATUS=...") to the socket named by $NOTIFY_SOCKET (a
// path, or '@' for the abstract namespace), as systemd's Type=notify units and the tests wait for
// it. Without $NOTIFY_SOCKET it does nothing; a socket that cannot be reached is not an error of
// the run (the manager will time the service out and say so). Non-RT (the main thread).
void notify_service(std::string_view state) noexcept;

}  // namespace saw::apps
