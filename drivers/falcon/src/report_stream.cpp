#include "saw/drivers/falcon/report_stream.hpp"

#include <algorithm>
#include <cstring>

namespace saw::drivers::falcon {

void ReportStream::push(std::span<const std::uint8_t> bytes) noexcept {
  if (bytes.size() >= capacity) bytes = bytes.last(capacity);
  if (count_ + bytes.size() > capacity) {
    const std::size_t drop = count_ + bytes.size() - capacity;
    std::memmove(buffer_.data(), buffer_.data() + drop, count_ - drop);
    count_ -= drop;
  }
  std::copy(bytes.begin(), bytes.end(), buffer_.begin() + static_cast<std::ptrdiff_t>(count_));
  count_ += bytes.size();
}

bool ReportStream::take_newest(Packet& out) noexcept {
  std::size_t p = 0, keep = count_;  // keep: where the unconsumed tail starts
  std::size_t newest = count_;
  std::uint64_t frames = 0;
  while (p < count_) {
    if (buffer_[p] != packet_start) {
      ++p;
      continue;
    }
    if (count_ - p < packet_size) {  // the start of a frame still arriving
      keep = p;
      break;
    }
    if (buffer_[p + packet_size - 1] == packet_end) {
      newest = p;
      ++frames;
      p += packet_size;
    } else {
      ++p;  // a '<' that frames nothing: resynchronise on the next
    }
  }
  const bool found = newest < count_;
  if (found) {
    std::memcpy(out.data(), buffer_.data() + newest, packet_size);
    skipped_ += frames - 1;
  }
  std::memmove(buffer_.data(), buffer_.data() + keep, count_ - keep);
  count_ -= keep;
  return found;
}

}  // namespace saw::drivers::falcon
