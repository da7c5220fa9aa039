// ASan builds only: lets Fast DDS 2.9's RTPSWriter and RTPSReader destructors delete their
// statistics objects with the wrong size, and nothing else.
//
// Why: Debian's libfastrtps 2.9 is built with statistics; ~RTPSWriter deletes a
// StatisticsWriterImpl (88 bytes) through a pointer whose type is 56 bytes (~RTPSReader does the
// same with its StatisticsReaderImpl), so ASan reports a
// new-delete-type-mismatch inside the library, not in our code. GCC 12's ASan cannot suppress
// that report by a suppressions file (no entry type reaches it: interceptor_via_fun,
// interceptor_via_lib and interceptor_name were tried), and ASAN_OPTIONS=new_delete_type_mismatch=0
// would hide the same defect in our own code. So this replaces sized operator delete: a call
// made from one of those destructors (by symbol name) frees without the size check; every
// other call goes on to ASan's own sized delete, which checks the size as before.
#include <dlfcn.h>

#include <cstddef>
#include <cstring>
#include <initializer_list>
#include <new>

namespace {

using SizedDelete = void (*)(void*, std::size_t);

SizedDelete next_sized_delete() {
  static const auto next = reinterpret_cast<SizedDelete>(dlsym(RTLD_NEXT, "_ZdlPvm"));
  return next;
}

// True when `caller` lies in ~RTPSWriter() or ~RTPSReader() of eprosima::fastrtps::rtps.
bool from_rtps_endpoint_destructor(void* caller) {
  Dl_info info{};
  if (dladdr(caller, &info) == 0 || info.dli_sname == nullptr) return false;
  for (const char* destructor : {"_ZN8eprosima8fastrtps4rtps10RTPSWriterD",   // D0, D1, D2
                                 "_ZN8eprosima8fastrtps4rtps10RTPSReaderD"})
    if (std::strncmp(info.dli_sname, destructor, std::strlen(destructor)) == 0) return true;
  return false;
}

}  // namespace

void operator delete(void* p, std::size_t size) noexcept {
  if (from_rtps_endpoint_destructor(__builtin_return_address(0))) {
    ::operator delete(p);  // unsized: ASan still checks that `p` came from new and is live
    return;
  }
  next_sized_delete()(p, size);
}
