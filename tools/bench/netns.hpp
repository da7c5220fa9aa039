// Network namespaces made and removed here: two joined by a veth pair ("Network 1H" on one
// machine), and two subnets joined by a router ("Network MH": nothing but unicast crosses it).
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

// Namespaces <prefix>-o-<pid> (the operator, 10.213.X.1), <prefix>-r-<pid> (the router: .254 on
// both subnets, forwarding) and <prefix>-p-<pid> (the patient, 10.214.X.1), each end's default
// route through the router; no multicast routing. With `netem` (a tc netem spec, e.g. "delay
// 20ms 5ms loss 1%"), the patient's link is shaped both ways (a kernel with sch_netem).
class RoutedNet {
 public:
  RoutedNet(const std::string& prefix, const std::string& netem) {
    const std::string tag = std::to_string(getpid());
    ns_o_ = prefix + "-o-" + tag;
    ns_r_ = prefix + "-r-" + tag;
    ns_p_ = prefix + "-p-" + tag;
    const std::string x = std::to_string(getpid() % 200 + 10);
    addr_o_ = "10.213." + x + ".1";
    addr_p_ = "10.214." + x + ".1";
    const std::string ro = "10.213." + x + ".254", rp = "10.214." + x + ".254";
    const std::string o = " -n " + ns_o_ + " ", r = " -n " + ns_r_ + " ", p = " -n " + ns_p_ + " ";
    const std::string vo = ("ro" + tag).substr(0, 15), vro = ("rro" + tag).substr(0, 15);
    const std::string vp = ("rp" + tag).substr(0, 15), vrp = ("rrp" + tag).substr(0, 15);
    std::string setup = "ip netns add " + ns_o_ + " && ip netns add " + ns_r_ + " && ip netns add " + ns_p_;
    setup += " && ip link add " + vo + " netns " + ns_o_ + " type veth peer name " + vro + " netns " + ns_r_;
    setup += " && ip link add " + vp + " netns " + ns_p_ + " type veth peer name " + vrp + " netns " + ns_r_;
    setup += " && ip" + o + "addr add " + addr_o_ + "/24 dev " + vo + " && ip" + r + "addr add " + ro +
             "/24 dev " + vro + " && ip" + p + "addr add " + addr_p_ + "/24 dev " + vp + " && ip" + r +
             "addr add " + rp + "/24 dev " + vrp;
    for (const auto& [ns, dev] : {std::pair{o, vo}, std::pair{r, vro}, std::pair{r, vrp}, std::pair{p, vp}})
      setup += " && ip" + ns + "link set " + dev + " up";
    setup += " && ip" + o + "link set lo up && ip" + r + "link set lo up && ip" + p + "link set lo up";
    setup += " && ip netns exec " + ns_r_ + " sysctl -qw net.ipv4.ip_forward=1";
    setup += " && ip" + o + "route add default via " + ro + " && ip" + p + "route add default via " + rp;
    if (!netem.empty())
      setup += " && tc" + r + "qdisc add dev " + vrp + " root netem " + netem + " && tc" + p +
               "qdisc add dev " + vp + " root netem " + netem;
    ok_ = std::system((setup + " 2>/dev/null").c_str()) == 0;
    if (!ok_) remove();
  }
  ~RoutedNet() { remove(); }
  RoutedNet(const RoutedNet&) = delete;
  RoutedNet& operator=(const RoutedNet&) = delete;

  bool ok() const { return ok_; }
  const std::string& ns_operator() const { return ns_o_; }
  const std::string& ns_patient() const { return ns_p_; }
  const std::string& addr_operator() const { return addr_o_; }
  const std::string& addr_patient() const { return addr_p_; }

 private:
  void remove() {
    (void)std::system(("ip netns del " + ns_o_ + " 2>/dev/null; ip netns del " + ns_r_ +
                       " 2>/dev/null; ip netns del " + ns_p_ + " 2>/dev/null")
                          .c_str());
  }
  std::string ns_o_, ns_r_, ns_p_, addr_o_, addr_p_;
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
