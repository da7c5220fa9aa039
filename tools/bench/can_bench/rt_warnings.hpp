// What the tasks could not get (SCHED_FIFO, affinity, locked memory), said once in the header.
#pragma once

#include <string>
#include <vector>

#include "saw/manager.hpp"

namespace saw::bench::can_bench {

// Every window starts a manager of its own: each warning is kept once, however many say it.
void note_warnings(const saw::Manager& m);
const std::vector<std::string>& rt_warnings();

}  // namespace saw::bench::can_bench
