// The summary saw-rt prints when a deployment ends: task statistics and summary columns.
#pragma once

#include <cstdio>

#include "saw/deploy/deployment.hpp"

namespace saw::apps {

// Per task: period, cycles, overruns, missed periods, wake-up latency; per component, each
// ColumnUse::summary column's latest value as its package formats it; the recorder's counts.
void print_summary(std::FILE* out, const deploy::Deployment& d, const deploy::ComponentRegistry& registry,
                   double seconds);

}  // namespace saw::apps
