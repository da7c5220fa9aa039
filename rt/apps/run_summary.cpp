#include "run_summary.hpp"

#include <sys/utsname.h>

#include <cstring>
#include <vector>

namespace saw::apps {
namespace {

void print_tasks(std::FILE* out, const deploy::Deployment& d) {
  std::fprintf(out, "  %-14s %8s %10s %9s %9s %9s %9s %9s %9s\n", "task", "period", "cycles", "overruns",
               "missed", "lat.min", "lat.mean", "lat.p99", "lat.max");
  for (const Component* c : d.components()) {
    const auto* t = dynamic_cast<const Task*>(c);
    if (t == nullptr) continue;
    const auto s = t->statistics();
    const auto& h = t->wakeup_histogram();
    std::fprintf(out, "  %-14s %6.2fms %10llu %9llu %9llu %7.1fus %7.1fus %7.1fus %7.1fus\n",
                 t->name().c_str(), static_cast<double>(t->config().period.count()) * 1e-6,
                 static_cast<unsigned long long>(s.cycles), static_cast<unsigned long long>(s.overruns),
                 static_cast<unsigned long long>(s.missed_periods), static_cast<double>(h.min()) / 1e3,
                 h.mean() / 1e3, static_cast<double>(h.percentile(0.99)) / 1e3,
                 static_cast<double>(h.max()) / 1e3);
  }
}

// Each line of a formatted summary, prefixed with the component's name.
void print_columns(std::FILE* out, const Component& c, const deploy::ComponentRegistry& registry) {
  const StateTable& table = c.state_table();
  if (!table.finalized() || table.rows_written() == 0) return;
  std::vector<std::byte> value;
  for (std::uint32_t i = 0; i < table.column_count(); ++i) {
    if (table.column_use(i) != ColumnUse::summary) continue;
    const TypeInfo type = table.column_type(i);
    const deploy::SummaryFormat* format = registry.summary_format(type);
    if (format == nullptr) continue;
    value.assign(type.size, std::byte{0});
    if (table.read_latest_erased(i, value.data(), nullptr) != Status::ok) continue;
    const std::string text = (*format)(value.data());
    for (std::size_t start = 0; start < text.size();) {
      const auto end = std::min(text.find('\n', start), text.size());
      std::fprintf(out, "  %s: %s\n", c.name().c_str(), text.substr(start, end - start).c_str());
      start = end + 1;
    }
  }
}

}  // namespace

void print_summary(std::FILE* out, const deploy::Deployment& d, const deploy::ComponentRegistry& registry,
                   double seconds) {
  std::fprintf(out, "summary of '%s' (%s clock, %.3f s):\n", d.name().c_str(),
               d.clock() == deploy::Clock::stepped ? "stepped" : "real", seconds);
  // The kernel the figures come from: a PREEMPT_RT one says so in its version string.
  if (utsname u{}; uname(&u) == 0)
    std::fprintf(out, "  kernel: %s %s (%s)\n", u.release, u.version,
                 std::strstr(u.version, "PREEMPT_RT") != nullptr ? "PREEMPT_RT" : "not PREEMPT_RT");
  print_tasks(out, d);
  for (const Component* c : d.components()) print_columns(out, *c, registry);
  if (const auto* r = d.recorder())
    std::fprintf(out, "  recorder: %llu rows to %s, %llu rows lost\n",
                 static_cast<unsigned long long>(r->rows()), r->path().c_str(),
                 static_cast<unsigned long long>(r->lost_rows()));
}

}  // namespace saw::apps
