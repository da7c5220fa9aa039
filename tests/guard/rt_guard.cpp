// The RT guard of the guard test binary: everything a thread inside an RT path
// (saw::in_rt_context()) does that an RT path must not do is counted as a violation.
//
// Two instruments, because neither alone sees everything:
//
// 1. Interposition. This binary defines the libc functions below, so every call that goes
//    through the symbol table (the tests, the project's static libraries, inline code from
//    libstdc++'s headers, libstdc++.so and other shared libraries) reaches them first; each
//    counts the call if the calling thread is in an RT path, then forwards to libc's own
//    (libc's calls to itself, e.g. fprintf's internal write, are not seen and not counted twice).
//    - allocations: malloc, calloc, realloc, aligned_alloc, memalign, posix_memalign;
//    - locks: pthread_mutex_{,timed,clock}lock, pthread_rwlock_{rd,wr}lock and their timed
//      and clock variants (std::mutex, std::shared_mutex), whether or not they would block;
//    - waits: pthread_cond_{wait,timedwait,clockwait} (std::condition_variable),
//      sem_{wait,timedwait,clockwait}, and syscall(SYS_futex) with a waiting operation (libstdc++
//      12's atomic::wait and std::counting_semaphore call syscall() from inline header code, so
//      they land here; FUTEX_WAKE is not a wait and is counted apart, as futex_wakes);
//    - stdio: the printf family (and the _FORTIFY_SOURCE __*_chk ones), puts, fputs, fputc,
//      putc, putchar, fwrite, fflush, perror, and write()/writev() to fd 1 or 2.
//    A call counts even when it returns at once (an uncontended lock, a zero timeout);
//    trylocks are not counted. Interposition cannot see a wait libc makes internally (a
//    contended lock's futex), a blocking read() or sleep, or an inline `syscall` instruction:
//    the second instrument sees those when they block.
//
// 2. Per-thread resource usage. The task loops call saw::RtCycleScope's observer when a
//    thread wakes for a cycle and before it sleeps again (rt_context.hpp); this guard installs
//    one that reads getrusage(RUSAGE_THREAD) at both ends and counts the difference in
//    - voluntary context switches: the thread blocked itself (a futex, a sleep, a blocking
//      read or write, a page fault that had to wait). A periodic task's one sleep per cycle
//      falls between end and begin and is not counted; preemption is an involuntary switch
//      and is not counted either, so a busy machine adds nothing here.
//    - minor page faults. The binary mlockall()s at start-up (MCL_CURRENT | MCL_FUTURE, as
//      saw-rt does through the manager), so every mapping is populated when it is made and a
//      fault in a cycle is memory the task itself left unlocked. Faults are counted from the
//      first cycle, like everything else; memory_locked() says whether the lock succeeded.
//      Without it, first touches of fresh memory fault and no test can require zero, so a
//      clean-path test checks less than it says: guard_support.hpp makes that a failure in CI
//      and a skip that says why elsewhere, never a silent pass.
//    getrusage costs about 0.5 µs (measured on the development VM), twice per cycle, and only
//    here: outside the guard the observer is null and a cycle pays one atomic load.
//
// Nothing is reset while tasks run: a GuardWindow is opened before the components exist, so
// the checks start at each RT thread's first cycle and lazy initialisation is caught. What
// runs before the first cycle (constructors, connect, start, the thread's own set-up) is not
// in an RT path and is not counted.
#include "rt_guard.hpp"

#include <dlfcn.h>
#include <linux/futex.h>
#include <pthread.h>
#include <semaphore.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "saw/rt_context.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
}

namespace {

enum class Kind : int { allocation, lock, wait, stdio, voluntary_switch, minor_fault };
constexpr const char* kind_names[] = {"allocation",       "lock",      "blocking wait", "stdio",
                                      "voluntary switch", "page fault"};

struct Counters {
  std::atomic<std::uint64_t> allocations{0}, locks{0}, waits{0}, stdio{0}, voluntary_switches{0},
      minor_faults{0}, futex_wakes{0}, cycles{0};
  std::atomic<std::size_t> first_size{0};
  std::atomic<int> first_kind{-1};
  std::atomic<const char*> first_task{nullptr};
};
Counters counters;

// The task whose cycle this thread is running (set by the cycle observer; for messages).
constinit thread_local const char* current_task = nullptr;

void note_first(Kind k) noexcept {
  int none = -1;
  if (counters.first_kind.compare_exchange_strong(none, static_cast<int>(k), std::memory_order_relaxed))
    counters.first_task.store(current_task, std::memory_order_relaxed);
}

void note(std::atomic<std::uint64_t>& counter, Kind k, std::uint64_t n = 1) noexcept {
  counter.fetch_add(n, std::memory_order_relaxed);
  note_first(k);
}

void note_allocation(std::size_t size) noexcept {
  if (!saw::in_rt_context()) return;
  std::size_t none = 0;
  (void)counters.first_size.compare_exchange_strong(none, size, std::memory_order_relaxed);
  note(counters.allocations, Kind::allocation);
}
void note_lock() noexcept {
  if (saw::in_rt_context()) note(counters.locks, Kind::lock);
}
void note_wait() noexcept {
  if (saw::in_rt_context()) note(counters.waits, Kind::wait);
}
void note_stdio() noexcept {
  if (saw::in_rt_context()) note(counters.stdio, Kind::stdio);
}

// The cycle observer: resource usage of this thread between wake-up and the next sleep.
constinit thread_local rusage at_begin{};
constinit thread_local bool begun = false;

void cycle_begin(const char* task) noexcept {
  current_task = task;
  if (!saw::in_rt_context()) return;
  begun = getrusage(RUSAGE_THREAD, &at_begin) == 0;
}

void cycle_end(const char*) noexcept {
  if (!saw::in_rt_context() || !begun) return;
  begun = false;
  rusage now{};
  if (getrusage(RUSAGE_THREAD, &now) != 0) return;
  counters.cycles.fetch_add(1, std::memory_order_relaxed);
  if (const auto n = static_cast<std::uint64_t>(now.ru_nvcsw - at_begin.ru_nvcsw); n > 0)
    note(counters.voluntary_switches, Kind::voluntary_switch, n);
  if (const auto n = static_cast<std::uint64_t>(now.ru_minflt - at_begin.ru_minflt); n > 0)
    note(counters.minor_faults, Kind::minor_fault, n);
}

constexpr saw::RtCycleObserver observer{cycle_begin, cycle_end};

// The functions this file replaces, as libc defines them.
template <class Fn>
Fn next(const char* name, const char* version = nullptr) noexcept {
  void* p = version != nullptr ? dlvsym(RTLD_NEXT, name, version) : nullptr;
  if (p == nullptr) p = dlsym(RTLD_NEXT, name);
  if (p == nullptr) std::abort();  // the guard cannot forward: nothing it reports would hold
  return reinterpret_cast<Fn>(p);
}

struct Real {
  decltype(&pthread_mutex_lock) mutex_lock = next<decltype(&pthread_mutex_lock)>("pthread_mutex_lock");
  decltype(&pthread_mutex_timedlock) mutex_timedlock =
      next<decltype(&pthread_mutex_timedlock)>("pthread_mutex_timedlock");
  decltype(&pthread_mutex_clocklock) mutex_clocklock =
      next<decltype(&pthread_mutex_clocklock)>("pthread_mutex_clocklock");
  decltype(&pthread_rwlock_rdlock) rdlock = next<decltype(&pthread_rwlock_rdlock)>("pthread_rwlock_rdlock");
  decltype(&pthread_rwlock_wrlock) wrlock = next<decltype(&pthread_rwlock_wrlock)>("pthread_rwlock_wrlock");
  decltype(&pthread_rwlock_timedrdlock) timedrdlock =
      next<decltype(&pthread_rwlock_timedrdlock)>("pthread_rwlock_timedrdlock");
  decltype(&pthread_rwlock_timedwrlock) timedwrlock =
      next<decltype(&pthread_rwlock_timedwrlock)>("pthread_rwlock_timedwrlock");
  decltype(&pthread_rwlock_clockrdlock) clockrdlock =
      next<decltype(&pthread_rwlock_clockrdlock)>("pthread_rwlock_clockrdlock");
  decltype(&pthread_rwlock_clockwrlock) clockwrlock =
      next<decltype(&pthread_rwlock_clockwrlock)>("pthread_rwlock_clockwrlock");
  // The condition variable functions have an old (2.2.5) and a current (2.3.2) version.
  decltype(&pthread_cond_wait) cond_wait =
      next<decltype(&pthread_cond_wait)>("pthread_cond_wait", "GLIBC_2.3.2");
  decltype(&pthread_cond_timedwait) cond_timedwait =
      next<decltype(&pthread_cond_timedwait)>("pthread_cond_timedwait", "GLIBC_2.3.2");
  decltype(&pthread_cond_clockwait) cond_clockwait =
      next<decltype(&pthread_cond_clockwait)>("pthread_cond_clockwait");
  decltype(&sem_wait) sem_wait_fn = next<decltype(&sem_wait)>("sem_wait");
  decltype(&sem_timedwait) sem_timedwait_fn = next<decltype(&sem_timedwait)>("sem_timedwait");
  decltype(&sem_clockwait) sem_clockwait_fn = next<decltype(&sem_clockwait)>("sem_clockwait");
  long (*syscall_fn)(long, ...) = next<long (*)(long, ...)>("syscall");
  decltype(&vfprintf) vfprintf_fn = next<decltype(&vfprintf)>("vfprintf");
  decltype(&vdprintf) vdprintf_fn = next<decltype(&vdprintf)>("vdprintf");
  int (*vfprintf_chk)(FILE*, int, const char*,
                      va_list) = next<int (*)(FILE*, int, const char*, va_list)>("__vfprintf_chk");
  decltype(&puts) puts_fn = next<decltype(&puts)>("puts");
  decltype(&fputs) fputs_fn = next<decltype(&fputs)>("fputs");
  decltype(&fputc) fputc_fn = next<decltype(&fputc)>("fputc");
  decltype(&putc) putc_fn = next<decltype(&putc)>("putc");
  decltype(&putchar) putchar_fn = next<decltype(&putchar)>("putchar");
  decltype(&fwrite) fwrite_fn = next<decltype(&fwrite)>("fwrite");
  decltype(&fflush) fflush_fn = next<decltype(&fflush)>("fflush");
  decltype(&perror) perror_fn = next<decltype(&perror)>("perror");
  decltype(&write) write_fn = next<decltype(&write)>("write");
  decltype(&writev) writev_fn = next<decltype(&writev)>("writev");
};
// On first use (stdio may be called before this file's statics are built), and once at start-up
// below so that no RT thread is the first.
const Real& real() noexcept {
  static const Real r;
  return r;
}
[[maybe_unused]] const Real& resolved_early = real();

// As saw-rt: every page mapped now or later is present, so a cycle's page fault is a finding.
// The errno is kept so that a test which cannot require zero faults can say why.
const int lock_errno = mlockall(MCL_CURRENT | MCL_FUTURE) == 0 ? 0 : errno;
const bool locked = lock_errno == 0;
[[maybe_unused]] const bool installed = (saw::set_rt_cycle_observer(&observer), true);

bool is_futex_wait(long op) noexcept {
  switch (op & FUTEX_CMD_MASK) {
    case FUTEX_WAIT:
    case FUTEX_WAIT_BITSET:
    case FUTEX_LOCK_PI:
    case FUTEX_LOCK_PI2:
    case FUTEX_WAIT_REQUEUE_PI:
      return true;
    default:
      return false;
  }
}

bool is_std_stream(int fd) noexcept { return fd == STDOUT_FILENO || fd == STDERR_FILENO; }

}  // namespace

namespace saw::testing {

GuardWindow::GuardWindow() noexcept {
  counters.first_kind.store(-1, std::memory_order_relaxed);
  counters.first_task.store(nullptr, std::memory_order_relaxed);
  counters.first_size.store(0, std::memory_order_relaxed);
  const auto get = [](const std::atomic<std::uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  start_.allocations = get(counters.allocations);
  start_.locks = get(counters.locks);
  start_.waits = get(counters.waits);
  start_.stdio = get(counters.stdio);
  start_.voluntary_switches = get(counters.voluntary_switches);
  start_.minor_faults = get(counters.minor_faults);
  start_.futex_wakes = get(counters.futex_wakes);
  start_.cycles = get(counters.cycles);
}

GuardCounts GuardWindow::counts() const {
  const auto since = [](const std::atomic<std::uint64_t>& a, std::uint64_t s) {
    return a.load(std::memory_order_relaxed) - s;
  };
  GuardCounts c;
  c.allocations = since(counters.allocations, start_.allocations);
  c.locks = since(counters.locks, start_.locks);
  c.waits = since(counters.waits, start_.waits);
  c.stdio = since(counters.stdio, start_.stdio);
  c.voluntary_switches = since(counters.voluntary_switches, start_.voluntary_switches);
  c.minor_faults = since(counters.minor_faults, start_.minor_faults);
  c.futex_wakes = since(counters.futex_wakes, start_.futex_wakes);
  c.cycles = since(counters.cycles, start_.cycles);
  c.first_allocation_size = counters.first_size.load(std::memory_order_relaxed);
  if (const int k = counters.first_kind.load(std::memory_order_relaxed); k >= 0) {
    const char* task = counters.first_task.load(std::memory_order_relaxed);
    c.first_violation = std::string(kind_names[k]) + " in task '" + (task ? task : "?") + "'";
  }
  return c;
}

bool memory_locked() noexcept { return locked; }

std::string memory_lock_error() {
  if (locked) return "";
  std::string why = std::string("mlockall(MCL_CURRENT | MCL_FUTURE) failed: ") + std::strerror(lock_errno);
  if (rlimit r{}; getrlimit(RLIMIT_MEMLOCK, &r) == 0 && r.rlim_cur != RLIM_INFINITY)
    why += " (RLIMIT_MEMLOCK " + std::to_string(r.rlim_cur / 1024) + " KiB: run as root or raise ulimit -l)";
  return why;
}

std::string describe(const GuardCounts& c) {
  return "allocations " + std::to_string(c.allocations) + " (first " +
         std::to_string(c.first_allocation_size) + " B), locks " + std::to_string(c.locks) + ", waits " +
         std::to_string(c.waits) + ", stdio " + std::to_string(c.stdio) + ", voluntary switches " +
         std::to_string(c.voluntary_switches) + ", page faults " + std::to_string(c.minor_faults) + " over " +
         std::to_string(c.cycles) +
         " cycles; first: " + (c.first_violation.empty() ? "none" : c.first_violation);
}

}  // namespace saw::testing

extern "C" {

// Allocation.
void* malloc(std::size_t n) {
  note_allocation(n);
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t m) {
  note_allocation(n * m);
  return __libc_calloc(n, m);
}
void* realloc(void* p, std::size_t n) {
  note_allocation(n);
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
void* aligned_alloc(std::size_t a, std::size_t n) {
  note_allocation(n);
  return __libc_memalign(a, n);
}
void* memalign(std::size_t a, std::size_t n) {
  note_allocation(n);
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, std::size_t a, std::size_t n) {
  note_allocation(n);
  void* p = __libc_memalign(a, n);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}

// Locks.
int pthread_mutex_lock(pthread_mutex_t* m) {
  note_lock();
  return real().mutex_lock(m);
}
int pthread_mutex_timedlock(pthread_mutex_t* m, const timespec* t) {
  note_lock();
  return real().mutex_timedlock(m, t);
}
int pthread_mutex_clocklock(pthread_mutex_t* m, clockid_t c, const timespec* t) {
  note_lock();
  return real().mutex_clocklock(m, c, t);
}
int pthread_rwlock_rdlock(pthread_rwlock_t* l) {
  note_lock();
  return real().rdlock(l);
}
int pthread_rwlock_wrlock(pthread_rwlock_t* l) {
  note_lock();
  return real().wrlock(l);
}
int pthread_rwlock_timedrdlock(pthread_rwlock_t* l, const timespec* t) {
  note_lock();
  return real().timedrdlock(l, t);
}
int pthread_rwlock_timedwrlock(pthread_rwlock_t* l, const timespec* t) {
  note_lock();
  return real().timedwrlock(l, t);
}
int pthread_rwlock_clockrdlock(pthread_rwlock_t* l, clockid_t c, const timespec* t) {
  note_lock();
  return real().clockrdlock(l, c, t);
}
int pthread_rwlock_clockwrlock(pthread_rwlock_t* l, clockid_t c, const timespec* t) {
  note_lock();
  return real().clockwrlock(l, c, t);
}

// Waits.
int pthread_cond_wait(pthread_cond_t* cv, pthread_mutex_t* m) {
  note_wait();
  return real().cond_wait(cv, m);
}
int pthread_cond_timedwait(pthread_cond_t* cv, pthread_mutex_t* m, const timespec* t) {
  note_wait();
  return real().cond_timedwait(cv, m, t);
}
int pthread_cond_clockwait(pthread_cond_t* cv, pthread_mutex_t* m, clockid_t c, const timespec* t) {
  note_wait();
  return real().cond_clockwait(cv, m, c, t);
}
int sem_wait(sem_t* s) {
  note_wait();
  return real().sem_wait_fn(s);
}
int sem_timedwait(sem_t* s, const timespec* t) {
  note_wait();
  return real().sem_timedwait_fn(s, t);
}
int sem_clockwait(sem_t* s, clockid_t c, const timespec* t) {
  note_wait();
  return real().sem_clockwait_fn(s, c, t);
}
// syscall(2) takes at most six arguments after the number; reading six is what libc's own
// wrapper does (the unused ones are whatever the registers hold), and the kernel ignores them.
long syscall(long number, ...) {
  va_list ap;
  va_start(ap, number);
  long a[6];
  for (auto& x : a) x = va_arg(ap, long);
  va_end(ap);
  if (saw::in_rt_context() && (number == SYS_futex || number == SYS_futex_waitv)) {
    if (number == SYS_futex_waitv || is_futex_wait(a[1]))
      note_wait();
    else if ((a[1] & FUTEX_CMD_MASK) == FUTEX_WAKE)
      counters.futex_wakes.fetch_add(1, std::memory_order_relaxed);
  }
  return real().syscall_fn(number, a[0], a[1], a[2], a[3], a[4], a[5]);
}

// Stdio.
int printf(const char* f, ...) {
  note_stdio();
  va_list ap;
  va_start(ap, f);
  const int r = real().vfprintf_fn(stdout, f, ap);
  va_end(ap);
  return r;
}
int fprintf(FILE* s, const char* f, ...) {
  note_stdio();
  va_list ap;
  va_start(ap, f);
  const int r = real().vfprintf_fn(s, f, ap);
  va_end(ap);
  return r;
}
int dprintf(int fd, const char* f, ...) {
  note_stdio();
  va_list ap;
  va_start(ap, f);
  const int r = real().vdprintf_fn(fd, f, ap);
  va_end(ap);
  return r;
}
int vprintf(const char* f, va_list ap) {
  note_stdio();
  return real().vfprintf_fn(stdout, f, ap);
}
int vfprintf(FILE* s, const char* f, va_list ap) {
  note_stdio();
  return real().vfprintf_fn(s, f, ap);
}
int vdprintf(int fd, const char* f, va_list ap) {
  note_stdio();
  return real().vdprintf_fn(fd, f, ap);
}
int __printf_chk(int flag, const char* f, ...) {
  note_stdio();
  va_list ap;
  va_start(ap, f);
  const int r = real().vfprintf_chk(stdout, flag, f, ap);
  va_end(ap);
  return r;
}
int __fprintf_chk(FILE* s, int flag, const char* f, ...) {
  note_stdio();
  va_list ap;
  va_start(ap, f);
  const int r = real().vfprintf_chk(s, flag, f, ap);
  va_end(ap);
  return r;
}
int __vprintf_chk(int flag, const char* f, va_list ap) {
  note_stdio();
  return real().vfprintf_chk(stdout, flag, f, ap);
}
int __vfprintf_chk(FILE* s, int flag, const char* f, va_list ap) {
  note_stdio();
  return real().vfprintf_chk(s, flag, f, ap);
}
int puts(const char* s) {
  note_stdio();
  return real().puts_fn(s);
}
int fputs(const char* s, FILE* f) {
  note_stdio();
  return real().fputs_fn(s, f);
}
int fputc(int c, FILE* f) {
  note_stdio();
  return real().fputc_fn(c, f);
}
int putc(int c, FILE* f) {
  note_stdio();
  return real().putc_fn(c, f);
}
int putchar(int c) {
  note_stdio();
  return real().putchar_fn(c);
}
std::size_t fwrite(const void* p, std::size_t size, std::size_t n, FILE* f) {
  note_stdio();
  return real().fwrite_fn(p, size, n, f);
}
int fflush(FILE* f) {
  note_stdio();
  return real().fflush_fn(f);
}
void perror(const char* s) {
  note_stdio();
  real().perror_fn(s);
}
ssize_t write(int fd, const void* p, std::size_t n) {
  if (is_std_stream(fd)) note_stdio();
  return real().write_fn(fd, p, n);
}
ssize_t writev(int fd, const iovec* v, int n) {
  if (is_std_stream(fd)) note_stdio();
  return real().writev_fn(fd, v, n);
}

}  // extern "C"
