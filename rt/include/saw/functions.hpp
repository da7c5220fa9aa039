// Function objects of a required interface: the client's typed handles to a server's commands.
#pragma once

#include <string>

#include "saw/command_kind.hpp"
#include "saw/provided_interface.hpp"

namespace saw {

// Call these from the client component's own thread: each connection's mailbox has one producer.
// Manager::connect() binds them; until then every call returns Status::disconnected.
class FunctionBase {
 public:
  explicit FunctionBase(Signature s) : signature_(s) {}
  FunctionBase(const FunctionBase&) = delete;
  FunctionBase& operator=(const FunctionBase&) = delete;

  const Signature& signature() const noexcept { return signature_; }
  bool is_bound() const noexcept { return bound_; }

 protected:
  Status queue(const void* arg, std::size_t size) const noexcept {
    if (!bound_) return Status::disconnected;
    if (binding_.mailbox != nullptr) return binding_.mailbox->push(binding_.target, arg, size);
    if (binding_.forward != nullptr) return (*binding_.forward)(arg);
    binding_.direct(arg);
    return Status::ok;
  }
  Status call_read(const void* arg, void* out) const noexcept {
    if (!bound_) return Status::disconnected;
    return binding_.command->read(arg, out);
  }
  // A value that came from another process and is not a valid T (a NaN, a bool that is not
  // 0 or 1, an enumerator out of range) is refused, never handed to the caller as a T.
  template <class T>
  Status checked(Status st, const T& out) const noexcept {
    if (st == Status::ok && binding_.check_values && !check_value(out)) return Status::invalid;
    return st;
  }

  Signature signature_;
  detail::FunctionBinding binding_{};
  bool bound_ = false;

 private:
  friend struct detail::Access;
  void bind(const detail::FunctionBinding& b) noexcept {
    binding_ = b;
    bound_ = true;
  }
  void unbind() noexcept {
    binding_ = {};
    bound_ = false;
  }
};

class FunctionVoid : public FunctionBase {
 public:
  FunctionVoid() : FunctionBase({CommandKind::void_command}) {}
  // Queues the command; queue_full (counted by the mailbox) if the server is behind.
  [[nodiscard]] Status operator()() const noexcept { return queue(nullptr, 0); }
};

template <Plain T>
class FunctionWrite : public FunctionBase {
 public:
  FunctionWrite() : FunctionBase({CommandKind::write, type_info_of<T>()}) {}
  [[nodiscard]] Status operator()(const T& value) const noexcept { return queue(&value, sizeof(T)); }
};

template <Plain T>
class FunctionRead : public FunctionBase {
 public:
  FunctionRead() : FunctionBase({CommandKind::read, type_info_of<T>()}) {}
  // The server's newest committed value.
  [[nodiscard]] Status operator()(T& out) const noexcept { return checked(call_read(nullptr, &out), out); }
  // With the row's tick and time (state-backed commands and proxies; a proxy gives tick 0).
  [[nodiscard]] Status operator()(T& out, RowStamp& stamp) const noexcept {
    if (!bound_) return Status::disconnected;
    if (binding_.stamped != nullptr) return checked((*binding_.stamped)(&out, stamp), out);
    if (binding_.command->table == nullptr) return Status::no_data;
    return binding_.command->table->read_latest_erased(binding_.command->column, &out, &stamp);
  }
  // The value the server had at time t: the newest row at or before t, from history.
  [[nodiscard]] Status at_or_before(TimeNs t, T& out, RowStamp* stamp = nullptr) const noexcept {
    if (!bound_) return Status::disconnected;
    if (binding_.command->table == nullptr) return Status::no_data;
    return binding_.command->table->read_at_or_before_erased(binding_.command->column, t, &out, stamp);
  }
};

template <Plain Q, Plain R>
class FunctionQualifiedRead : public FunctionBase {
 public:
  FunctionQualifiedRead()
      : FunctionBase({CommandKind::qualified_read, type_info_of<Q>(), type_info_of<R>()}) {}
  [[nodiscard]] Status operator()(const Q& qualifier, R& out) const noexcept {
    return checked(call_read(&qualifier, &out), out);
  }
};

}  // namespace saw
