// Invoker: a type-erased call target (function pointer plus object) that never allocates (internal).
#pragma once

namespace saw::detail {

// The argument pointers are checked against TypeInfo when interfaces are bound, so the
// casts inside the thunks are always to the right type.
struct Invoker {
  void (*fn)(void* self, const void* arg) = nullptr;
  void* self = nullptr;

  void operator()(const void* arg) const { fn(self, arg); }
  explicit operator bool() const noexcept { return fn != nullptr; }
};

}  // namespace saw::detail
