// Two network namespaces joined by a veth pair ("Network 1H" on one machine), made and removed here.
#pragma once

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace saw::bench {

// Namespaces sawlat-a-<pid> and sawlat-b-<pid>, addresses 10.212.X.1 (a) and .2 (b), lo up in
// both; nothing else is routed. ok() is false (with why()) where namespaces cannot be made.
class VethPair {
 public:
  explicit VethPair(const std::string& prefix) {
    const std::string tag = std::to_string(getpid());
    ns_a_ = prefix + "-a-" + tag;
    ns_b_ = prefix + "-b-" + tag;
    const std::string net = "10.212." + std::to_string(getpid() % 200 + 10);
    addr_a_ = net + ".1";
    addr_b_ = net + ".2";
    const std::string va = ("va" + tag).substr(0, 15), vb = ("vb" + tag).substr(0, 15);
    const std::string a = " -n " + ns_a_ + " ", b = " -n " + ns_b_ + " ";
    const std::string setup =
        "ip netns add " + ns_a_ + " && ip netns add " + ns_b_ + " && ip link add " + va +
        " type veth peer name " + vb + " && ip link set " + va + " netns " + ns_a_ + " && ip link set " + vb +
        " netns " + ns_b_ + " && ip" + a + "addr add " + addr_a_ + "/24 dev " + va + " && ip" + b +
        "addr add " + addr_b_ + "/24 dev " + vb + " && ip" + a + "link set " + va + " up && ip" + b +
        "link set " + vb + " up && ip" + a + "link set lo up && ip" + b + "link set lo up";
    ok_ = std::system((setup + " 2>/dev/null").c_str()) == 0;
    if (!ok_) remove();
  }
  ~VethPair() { remove(); }
  VethPair(const VethPair&) = delete;
  VethPair& operator=(const VethPair&) = delete;

  bool ok() const { return ok_; }
  const std::string& ns_a() const { return ns_a_; }
  const std::string& ns_b() const { return ns_b_; }
  const std::string& addr_a() const { return addr_a_; }
  const std::string& addr_b() const { return addr_b_; }

 private:
  void remove() {
    (void)std::system(
        ("ip netns del " + ns_a_ + " 2>/dev/null; ip netns del " + ns_b_ + " 2>/dev/null").c_str());
  }
  std::string ns_a_, ns_b_, addr_a_, addr_b_;
  bool ok_ = false;
};

// Moves the calling thread (call it before any other thread exists) into namespace `ns`;
// "" stays. Exits the process if it cannot: a measurement in the wrong namespace is worse.
inline void enter_netns(const std::string& ns) {
  if (ns.empty()) return;
  const int fd = open(("/var/run/netns/" + ns).c_str(), O_RDONLY);
  if (fd < 0 || setns(fd, CLONE_NEWNET) != 0) {
    std::perror(("setns " + ns).c_str());
    std::_Exit(3);
  }
  close(fd);
}

}  // namespace saw::bench
