#include "saw/deploy/recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include "saw/crtk.hpp"
#include "saw/rt_thread.hpp"

namespace saw::deploy {
namespace {

template <class T>
const T& as(const void* p) {
  return *static_cast<const T*>(p);
}
void number(std::string& out, double v) {
  char b[32];
  std::snprintf(b, sizeof b, ",%.9g", v);
  out += b;
}
void vec(std::string& out, const Vec3& v) {
  for (double x : v) number(out, x);
}

template <class T>
std::pair<std::string, ColumnFormat> entry(std::vector<std::string> names,
                                           void (*write)(const void*, std::string&)) {
  return {std::string(type_name<T>()), ColumnFormat{std::move(names), write}};
}

const std::vector<std::pair<std::string, ColumnFormat>>& formats() {
  static const std::vector<std::pair<std::string, ColumnFormat>> all = {
      entry<double>({""}, [](const void* p, std::string& o) { number(o, as<double>(p)); }),
      entry<float>({""}, [](const void* p, std::string& o) { number(o, as<float>(p)); }),
      entry<bool>({""}, [](const void* p, std::string& o) { o += as<bool>(p) ? ",1" : ",0"; }),
      entry<std::int32_t>(
          {""}, [](const void* p, std::string& o) { o += "," + std::to_string(as<std::int32_t>(p)); }),
      entry<std::int64_t>(
          {""}, [](const void* p, std::string& o) { o += "," + std::to_string(as<std::int64_t>(p)); }),
      entry<std::uint64_t>(
          {""}, [](const void* p, std::string& o) { o += "," + std::to_string(as<std::uint64_t>(p)); }),
      entry<Vec3>({".x", ".y", ".z"}, [](const void* p, std::string& o) { vec(o, as<Vec3>(p)); }),
      entry<Pose>({".x", ".y", ".z", ".qx", ".qy", ".qz", ".qw"},
                  [](const void* p, std::string& o) {
                    vec(o, as<Pose>(p).position);
                    for (double x : as<Pose>(p).orientation) number(o, x);
                  }),
      entry<Twist>({".vx", ".vy", ".vz", ".wx", ".wy", ".wz"},
                   [](const void* p, std::string& o) {
                     vec(o, as<Twist>(p).linear);
                     vec(o, as<Twist>(p).angular);
                   }),
      entry<Wrench>({".fx", ".fy", ".fz", ".tx", ".ty", ".tz"},
                    [](const void* p, std::string& o) {
                      vec(o, as<Wrench>(p).force);
                      vec(o, as<Wrench>(p).torque);
                    }),
      entry<JointState>({".q0", ".q1", ".q2"},
                        [](const void* p, std::string& o) {
                          for (int i = 0; i < 3; ++i)
                            number(o, as<JointState>(p).position[static_cast<std::size_t>(i)]);
                        }),
      entry<OperatingState>({""},
                            [](const void* p, std::string& o) {
                              o += ",";
                              o += to_string(as<OperatingState>(p).state);
                            }),
  };
  return all;
}

}  // namespace

const ColumnFormat* format_for(TypeInfo type) {
  for (const auto& [name, f] : formats())
    if (name == type.name) return &f;
  return nullptr;
}

Recorder::Recorder(std::string path, std::vector<Column> columns, int decimation)
    : path_(std::move(path)), columns_(std::move(columns)), decimation_(decimation < 1 ? 1 : decimation) {
  if (columns_.empty()) throw std::invalid_argument("recorder: no columns");
  file_ = std::fopen(path_.c_str(), "w");
  if (file_ == nullptr)
    throw std::runtime_error("recorder: cannot write " + path_ + ": " + std::strerror(errno));
  std::size_t largest = 0;
  std::string header = "time";
  for (const auto& c : columns_) {
    largest = std::max(largest, c.component->state_table().column_type(c.index).size);
    for (const auto& suffix : c.format->names) header += "," + c.name + suffix;
  }
  std::fprintf(file_, "%s\n", header.c_str());
  buffer_.resize(largest + 16);
}

Recorder::~Recorder() { stop(); }

void Recorder::collect(std::string& out) {
  const StateTable& clock = columns_.front().component->state_table();
  const auto written = clock.rows_written();
  // Keep two rows of margin from the writer, as the state table's own history reads do.
  const std::uint64_t oldest = written > clock.capacity() - 2 ? written - (clock.capacity() - 2) : 0;
  if (next_tick_ < oldest) {
    lost_.fetch_add(oldest - next_tick_, std::memory_order_relaxed);
    next_tick_ = oldest;
  }
  for (; next_tick_ < written; ++next_tick_) {
    if (next_tick_ % static_cast<std::uint64_t>(decimation_) != 0) continue;
    RowStamp stamp;
    line_.clear();
    bool ok = true;
    for (std::size_t i = 0; i < columns_.size() && ok; ++i) {
      const auto& c = columns_[i];
      const StateTable& t = c.component->state_table();
      const Status s = i == 0 ? t.read_tick_erased(c.index, next_tick_, buffer_.data(), &stamp)
                              : t.read_at_or_before_erased(c.index, stamp.time, buffer_.data(), nullptr);
      if (s != Status::ok) {
        ok = i != 0;  // a missing other column leaves empty cells; a lost clock row is lost
        for (std::size_t k = 0; k < c.format->names.size(); ++k) line_ += ",";
        continue;
      }
      c.format->write(buffer_.data(), line_);
    }
    if (!ok) {
      lost_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    char time[32];
    std::snprintf(time, sizeof time, "%.9f", static_cast<double>(stamp.time) * 1e-9);
    out += time;
    out += line_;
    out += '\n';
    rows_.fetch_add(1, std::memory_order_relaxed);
  }
}

void Recorder::poll() {
  if (file_ == nullptr) return;
  collected_.clear();
  collect(collected_);
  std::fwrite(collected_.data(), 1, collected_.size(), file_);
}

void Recorder::write_pending() {
  std::string chunk;
  {
    std::lock_guard lock(pending_mutex_);
    chunk.swap(pending_);
  }
  if (!chunk.empty()) std::fwrite(chunk.data(), 1, chunk.size(), file_);
}

void Recorder::start_thread() {
  collector_ = std::thread([this] {
    (void)rt::set_fifo(1);  // where it may not (no rtprio), it runs as a normal thread
    while (!stop_.load(std::memory_order_acquire)) {
      collected_.clear();
      collect(collected_);
      const auto rows = static_cast<std::uint64_t>(std::count(collected_.begin(), collected_.end(), '\n'));
      {
        std::lock_guard lock(pending_mutex_);
        if (pending_.size() + collected_.size() <= max_pending) {
          pending_ += collected_;
        } else {  // the disk is that far behind: these rows are lost, and counted
          rows_.fetch_sub(rows, std::memory_order_relaxed);
          lost_.fetch_add(rows, std::memory_order_relaxed);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
  writer_ = std::thread([this] {
    while (!stop_.load(std::memory_order_acquire)) {
      write_pending();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
}

void Recorder::stop() {
  stop_.store(true, std::memory_order_release);
  if (collector_.joinable()) collector_.join();
  if (writer_.joinable()) writer_.join();
  if (file_ != nullptr) {
    write_pending();
    poll();
    std::fclose(file_);
    file_ = nullptr;
  }
}

}  // namespace saw::deploy
