// Attachment: one exported component, mapped to DDS by its own thread (internal).
#pragma once

#include <atomic>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "dds_context.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/gateway/gateway.hpp"

namespace saw::gateway {

class Attachment {
 public:
  // Resolves the component through the bridge (waiting up to `timeout`), creates its topics.
  // `display_rate` (Hz, 0: none): the row-by-row states' display streams (GatewayConfig).
  Attachment(DdsContext& dds, const std::string& component, unsigned decimation, double display_rate,
             TimeNs timeout, std::function<void()> liveness_changed);
  ~Attachment();

  const std::vector<EndpointInfo>& endpoints() const noexcept { return endpoints_; }
  const std::string& component() const noexcept { return name_; }
  bool alive() const noexcept { return alive_.load(std::memory_order_acquire); }
  void add_stats(GatewayStats& s) const;
  // Starts the thread (after the gateway has published its first manifest).
  void start();
  // Joins its threads (idempotent). The gateway stops every attachment before destroying any:
  // a running one may call back into the gateway, which reads them all (publish_manifest).
  void stop();
  // FAULT on the operating state and "FAULT: <why>" on the error topic.
  void publish_fault(const std::string& why);
  // Until the readers have acknowledged the fault and error samples, or `deadline` (monotonic).
  void wait_for_acknowledgments(TimeNs deadline);

 private:
  struct StateOut {
    const Command* command;
    const Mapping* mapping;
    fdds::DataWriter* writer;
    std::vector<std::byte> value;
    std::vector<std::byte> previous = {};  // for states published on change
    unsigned every = 1;                    // of the published rows (a task's statistics: 1 in 10)
    fdds::DataWriter* display = nullptr;   // <topic>/display, at the display rate
    std::uint32_t offset = 0, size = 0;    // where its value sits in a row of the bridge's mirror
  };
  struct EventOut {
    Attachment* self;
    const Mapping* mapping;
    fdds::DataWriter* writer;
    bool fault_text = false;  // a FaultInfo: its text also goes to the CRTK error topic
  };
  struct QueryIn {
    const Command* command;  // of the query proxy (its own slot, used by the query thread only)
    fdds::DataReader* requests;
    fdds::DataWriter* replies;
    std::size_t arg_size, result_size;
  };
  struct CommandIn {
    const Command* command;
    const Mapping* mapping;
    fdds::DataReader* reader;
    std::vector<std::byte> value;
  };

  void run();
  // Reads a state from the mirror and writes it; with `only_if_changed`, only when it differs
  // from the last read. True if a sample went out.
  bool publish_state(StateOut& s, bool only_if_changed);
  // Every row the server wrote since the last one published (from the bridge's row history):
  // each `decimation`th to the full-rate topics, the newest to the display streams when due.
  // Rows overwritten before they were read (the gateway was a history behind) are counted.
  void publish_rows();
  // The row in block_: to the full-rate topics when `full` (each state its `every`), to the
  // display streams when `newest` and its time has reached the next display time.
  void publish_block(bool full, bool newest);
  void serve_queries();
  // A command value against the limits its component declares; the reason in `why` if outside.
  static bool within_limits(CommandIn& c, std::string& why);
  void reject(const std::string& command, const std::string& why);
  // A line on rt/<component>/error (crtk_msgs/StringStamped), CRTK's topic for errors.
  void publish_error(const std::string& text);

  DdsContext& dds_;
  std::string name_;
  unsigned decimation_;
  TimeNs display_period_;    // 0: no display streams
  TimeNs next_display_ = 0;  // the row time from which the next display sample is due
  // The run thread's place in the server's rows: the next row to publish (once known), rows since
  // the last full-rate one, full-rate rows published, and one row's block.
  bool rows_known_ = false;
  std::uint64_t next_row_ = 0;
  unsigned rows_ = 0;
  std::uint64_t published_rows_ = 0;
  std::vector<std::byte> block_;
  std::function<void()> liveness_changed_;
  std::unique_ptr<Component> component_;
  bridge::Proxy* proxy_ = nullptr;
  std::vector<EndpointInfo> endpoints_;
  std::vector<StateOut> states_;          // every decimated row
  std::vector<StateOut> changed_states_;  // latched, on change (an operating state without event)
  std::vector<StateOut> initial_states_;  // latched events' values at attach and reconnection
  std::vector<std::unique_ptr<EventOut>> events_;
  std::vector<CommandIn> commands_;
  // Qualified reads block for the server's answer: their own proxy (slot) and thread.
  std::unique_ptr<Component> query_component_;
  std::vector<QueryIn> queries_;
  std::unique_ptr<fdds::GuardCondition> query_stop_;
  std::thread query_thread_;
  std::atomic<std::uint64_t> queries_served_{0};
  fdds::DataWriter* error_writer_ = nullptr;
  fdds::DataWriter* fault_writer_ = nullptr;  // the OperatingState topic, if the component has one
  std::atomic<bool> alive_{true};
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> published_{0}, displayed_{0}, event_count_{0}, commands_in_{0}, rejected_{0},
      rows_skipped_{0};
  std::thread thread_;
};

}  // namespace saw::gateway
