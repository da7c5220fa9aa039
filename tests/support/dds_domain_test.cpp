// The DDS domain allocator of the tests and benchmarks (saw/testing/dds_domain.hpp and its Python
// twin): two claims in two processes never hold the same id, C++ and Python claimers exclude each
// other and draw from the same pool, a killed claimer's id is free again at once, a fixed id waits
// for its holder.
#include "saw/testing/dds_domain.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace {

using saw::testing::DdsDomain;
using saw::testing::DomainPool;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

// A lock directory of this test's own, so that a pool of one or two ids is deterministic.
DomainPool private_pool(const std::string& tag, std::vector<int> ids) {
  const fs::path dir =
      fs::path(::testing::TempDir()) / ("saw-domains-" + tag + "-" + std::to_string(getpid()));
  fs::remove_all(dir);
  return DomainPool{dir.string(), std::move(ids)};
}

// One line from fd within `timeout` (a bound for a process start, not a measurement), or "".
std::string read_line(int fd, std::chrono::milliseconds timeout) {
  std::string line;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    pollfd p{fd, POLLIN, 0};
    if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) <= 0) return "";
    char c = 0;
    if (::read(fd, &c, 1) != 1) return line;
    if (c == '\n') return line;
    line += c;
  }
}

// A claimer in another process: a forked child claiming from `pool` (or running `argv`, which
// prints its id), reporting its id on a pipe, holding its claim until told to go or killed.
class Claimer {
 public:
  explicit Claimer(const DomainPool& pool) {
    start([&] {
      try {
        DdsDomain d(pool);
        std::printf("%d\n", d.id());
        std::fflush(stdout);
        char c;
        while (::read(STDIN_FILENO, &c, 1) > 0) {
        }
        return 0;
      } catch (const std::exception&) {
        std::printf("-1\n");
        std::fflush(stdout);
        return 1;
      }
    });
  }
  explicit Claimer(const std::vector<std::string>& argv) {
    start([&] {
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      return 127;
    });
  }
  ~Claimer() {
    kill9();
    if (in_ >= 0) ::close(in_);
    if (out_ >= 0) ::close(out_);
  }
  Claimer(const Claimer&) = delete;
  Claimer& operator=(const Claimer&) = delete;

  // The id it holds; -1 if it could not claim one (or said nothing).
  int id() {
    if (!id_) {
      const std::string line = read_line(out_, 30s);
      id_ = line.empty() ? -1 : std::stoi(line);
    }
    return *id_;
  }
  // Its standard input closed: it lets go and exits (the claim may outlive this call briefly).
  void let_go() {
    if (in_ >= 0) ::close(in_);
    in_ = -1;
  }
  // SIGKILL and reaped: when this returns, the process and its descriptors are gone.
  void kill9() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }

 private:
  template <class F>
  void start(F child) {
    int to[2], from[2];
    ASSERT_EQ(::pipe2(to, O_CLOEXEC), 0);
    ASSERT_EQ(::pipe2(from, O_CLOEXEC), 0);
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(to[0], STDIN_FILENO);
      ::dup2(from[1], STDOUT_FILENO);
      // Nothing else of the parent's: not its end of our stdin (or we would never see it close),
      // not other claimers' pipes, not the parent's own claims.
      ::close_range(3, ~0U, 0);
      ::_exit(child());
    }
    ::close(to[0]);
    ::close(from[1]);
    in_ = to[1];
    out_ = from[0];
  }
  pid_t pid_ = -1;
  int in_ = -1, out_ = -1;
  std::optional<int> id_;
};

std::vector<std::string> python_holder(const DomainPool& pool) {
  std::string ids;
  for (const int id : pool.ids) ids += (ids.empty() ? "" : ",") + std::to_string(id);
  return {"python3", SAW_DDS_DOMAIN_PY, "--dir", pool.dir, "--ids", ids, "--hold"};
}

TEST(DdsDomain, TwoClaimsInTwoProcessesNeverHoldTheSameId) {
  const DomainPool pool = private_pool("two", {11, 12});
  Claimer other(pool);
  ASSERT_NE(other.id(), -1);
  const DdsDomain mine(pool);
  EXPECT_EQ(std::set<int>({other.id(), mine.id()}), std::set<int>({11, 12}));
  // Both held: a third claim (in this process too, on its own open file) finds none.
  EXPECT_THROW(DdsDomain{pool}, std::runtime_error);

  // The standard pool, in the shared directory, beside whatever else runs: never equal either.
  for (int i = 0; i < 20; ++i) {
    Claimer a(DomainPool::standard());
    const DdsDomain b;
    ASSERT_NE(a.id(), -1);
    EXPECT_NE(a.id(), b.id());
  }
}

TEST(DdsDomain, AKilledClaimersIdIsFreeAgain) {
  const DomainPool pool = private_pool("killed", {21});
  Claimer other(pool);
  ASSERT_EQ(other.id(), 21);
  EXPECT_THROW(DdsDomain{pool}, std::runtime_error);
  EXPECT_FALSE(DdsDomain::try_fixed(21, pool.dir).has_value());
  other.kill9();
  const DdsDomain mine(pool);  // no wait: the kernel dropped the lock with the process
  EXPECT_EQ(mine.id(), 21);
}

TEST(DdsDomain, CxxAndPythonClaimersExcludeEachOther) {
  if (std::system("python3 -c pass >/dev/null 2>&1") != 0) GTEST_SKIP() << "no python3 on PATH";
  const DomainPool pool = private_pool("py", {31, 32});
  Claimer python(python_holder(pool));
  ASSERT_NE(python.id(), -1) << "the Python claimer printed no id";
  const DdsDomain mine(pool);
  EXPECT_EQ(std::set<int>({python.id(), mine.id()}), std::set<int>({31, 32}));
  Claimer second(python_holder(pool));  // both held: the Python claimer finds none and says so
  EXPECT_EQ(second.id(), -1);
  const int pythons = python.id();
  python.kill9();
  const DdsDomain again(pool);
  EXPECT_EQ(again.id(), pythons);
}

TEST(DdsDomain, ThePythonTwinHasTheSamePoolAndDirectory) {
  if (std::system("python3 -c pass >/dev/null 2>&1") != 0) GTEST_SKIP() << "no python3 on PATH";
  const std::string module = fs::path(SAW_DDS_DOMAIN_PY).parent_path().parent_path().string();
  const std::string command = "python3 -c 'import sys; sys.path.insert(0, \"" + module +
                              "\"); from saw_testing import dds_domain as d; "
                              "print(d.lock_dir(), *d.POOL)'";
  FILE* p = ::popen(command.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, p)) out += buffer;
  ASSERT_EQ(::pclose(p), 0) << out;
  const DomainPool pool = DomainPool::standard();
  std::string expected = pool.dir;
  for (const int id : pool.ids) expected += " " + std::to_string(id);
  EXPECT_EQ(out, expected + "\n");
}

TEST(DdsDomain, AFixedIdWaitsForItsHolder) {
  const DomainPool pool = private_pool("fixed", {41});
  Claimer other(pool);
  ASSERT_EQ(other.id(), 41);
  EXPECT_FALSE(DdsDomain::try_fixed(41, pool.dir).has_value());
  other.let_go();
  const DdsDomain mine = DdsDomain::fixed(41, 30s, pool.dir);  // bounded: its exit is a process exit
  EXPECT_EQ(mine.id(), 41);
}

TEST(DdsDomain, TheProcessDomainIsOneIdOfThePoolAndTheDirectoryIsShared) {
  const int id = saw::testing::process_dds_domain();
  EXPECT_EQ(saw::testing::process_dds_domain(), id);
  const auto ids = DomainPool::standard().ids;
  EXPECT_NE(std::find(ids.begin(), ids.end(), id), ids.end()) << id;
  for (const int reserved : {0, 3, 7, 42, 229, 230, 231, 232})
    EXPECT_EQ(std::find(ids.begin(), ids.end(), reserved), ids.end()) << reserved;
  const DdsDomain another;  // another claim in the same process: another id
  EXPECT_NE(another.id(), id);

  const DomainPool pool = private_pool("modes", {51});
  const DdsDomain d(pool);
  struct stat dir = {};
  struct stat file = {};
  ASSERT_EQ(::stat(pool.dir.c_str(), &dir), 0);
  ASSERT_EQ(::stat((pool.dir + "/51").c_str(), &file), 0);
  EXPECT_EQ(dir.st_mode & 07777, 01777u) << "other users' tests make their lock files here";
  EXPECT_EQ(file.st_mode & 0777, 0644u) << "other users' tests open it to lock it";
}

}  // namespace
