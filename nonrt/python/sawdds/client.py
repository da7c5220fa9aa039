"""List a sawrt system's components, read their state and send them commands, over Cyclone DDS.

Loopback only unless CYCLONEDDS_URI says otherwise: the configuration below restricts Cyclone DDS
to interface ``lo`` with unicast discovery (lo has no multicast), finding Fast DDS participants at
their well-known ports.
"""
import os
import threading
import time

LOOPBACK_URI = (
    "<CycloneDDS><Domain Id='any'><General><Interfaces><NetworkInterface name='lo'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)
os.environ.setdefault("CYCLONEDDS_URI", LOOPBACK_URI)

from cyclonedds.core import DDSException, Policy, Qos  # noqa: E402  (after CYCLONEDDS_URI)
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

from . import msgs, security  # noqa: E402

XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)

# The gateway latches operating states, descriptions and settings' read-backs (RELIABLE,
# TRANSIENT_LOCAL, keep last 1, published on change) and keeps its error topic's last 16
# (TRANSIENT_LOCAL): a reader that asks for TRANSIENT_LOCAL gets them the moment it matches. Which
# topics are latched its manifest says (Endpoint.latched). (A TRANSIENT_LOCAL reader would not
# match a VOLATILE writer; a VOLATILE reader of a latched topic would wait for the next change.)


def latched(endpoint) -> bool:
    """Whether the gateway latches `endpoint`'s topic (its readers are then TRANSIENT_LOCAL, keep last 1)."""
    return bool(getattr(endpoint, "latched", False))


def display_topic(endpoint) -> str:
    """The topic on which the gateway also publishes `endpoint`'s state at its display rate
    (Endpoint.display_rate, Hz; 50 by default), "" when it has none. A live view reads it: the same
    values, a picture of them rather than every row. A recorder or a program that needs every row
    reads `endpoint.topic`."""
    return "" if latched(endpoint) else str(getattr(endpoint, "display_topic", "") or "")


def static_peers(env=None) -> list:
    """The peers ROS 2 users already name in $ROS_STATIC_PEERS (';'-separated addresses or host
    names, reached by unicast), [] when it is unset or empty."""
    text = (os.environ if env is None else env).get("ROS_STATIC_PEERS", "")
    return [p.strip() for p in text.split(";") if p.strip()]


def discovery_range(env=None) -> str:
    """ROS 2's $ROS_AUTOMATIC_DISCOVERY_RANGE: "SUBNET" (unset, SUBNET or SYSTEM_DEFAULT: multicast),
    "LOCALHOST" (this host only) or "OFF" (static peers only). Raises ValueError for another value."""
    value = (os.environ if env is None else env).get("ROS_AUTOMATIC_DISCOVERY_RANGE", "")
    if value in ("", "SUBNET", "SYSTEM_DEFAULT"):
        return "SUBNET"
    if value in ("LOCALHOST", "OFF"):
        return value
    raise ValueError(f"ROS_AUTOMATIC_DISCOVERY_RANGE={value}: expected SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT")


def interface_uri(interface: str = "lo", peers=("127.0.0.1",), multicast=None) -> str:
    """A CYCLONEDDS_URI restricting DDS to one network interface, by name ("eth1") or by one of its
    addresses ("192.168.1.20", "127.0.0.1" on any OS); `peers` for unicast discovery (loopback has
    no multicast), none to discover by multicast on that interface (unless `multicast` is False)."""
    peer_xml = "".join(f"<Peer address='{p}'/>" for p in peers)
    unicast = bool(peers) or multicast is False
    multicast = "false" if unicast else "true"
    discovery = (f"<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"
                 f"<Peers>{peer_xml}</Peers>") if unicast else ""
    import ipaddress
    try:
        ipaddress.ip_address(interface)
        nic = f"<NetworkInterface address='{interface}'/>"
    except ValueError:
        nic = f"<NetworkInterface name='{interface}'/>"
    return (f"<CycloneDDS><Domain Id='any'><General><Interfaces>{nic}"
            f"</Interfaces><AllowMulticast>{multicast}</AllowMulticast></General>"
            f"<Discovery>{discovery}</Discovery></Domain></CycloneDDS>")


def reader_qos(endpoint, depth: int = 16):
    """The QoS a reader of `endpoint` needs: reliable for events (and latched topics), best effort
    for state; TRANSIENT_LOCAL + keep last 1 for what the gateway latches."""
    if latched(endpoint):
        return Qos(Policy.Reliability.Reliable(0), Policy.Durability.TransientLocal, Policy.History.KeepLast(1),
                   XCDR1)
    reliable = endpoint.kind.endswith("event")
    return Qos(Policy.Reliability.Reliable(0) if reliable else Policy.Reliability.BestEffort,
               Policy.History.KeepLast(depth), XCDR1)


def error_qos(depth: int = 16):
    """The QoS of a reader of rt/<component>/error: reliable, TRANSIENT_LOCAL, the last `depth`."""
    return Qos(Policy.Reliability.Reliable(0), Policy.Durability.TransientLocal, Policy.History.KeepLast(depth), XCDR1)


class SecurityRefused(security.SecurityError, DDSException):
    """No participant: its enclave does not allow it. Both a SecurityError and, for callers that
    report a participant DDS would not make (sawgui), a DDSException."""

    def __init__(self, msg):
        security.SecurityError.__init__(self, msg)
        self.code, self.msg = DDSException.DDS_RETCODE_NOT_ALLOWED_BY_SECURITY, msg

    def __str__(self):
        return self.msg


class Client:
    def __init__(self, domain: int = 0):
        # ROS_SECURITY_ENABLE=true: the enclave's security, or SecurityError, never plaintext.
        try:
            security.secure_environment(domain)
        except security.SecurityError as e:
            raise SecurityRefused(str(e)) from None
        self.participant = DomainParticipant(domain)
        self._topics = {}
        self._topic_lock = threading.Lock()
        self._registry = DataReader(
            self.participant,
            self._topic("rt/saw/manifest", msgs.Manifest),
            qos=Qos(Policy.Reliability.Reliable(0), Policy.Durability.TransientLocal, Policy.History.KeepLast(256),
                    XCDR1),
        )
        self._manifests = {}
        self._writer_of = {}  # gateway name -> publication handle of its manifest writer

    def _topic(self, name, cls):
        # Under a lock: sawdds.live makes readers and writers from two threads.
        with self._topic_lock:
            if name not in self._topics:
                self._topics[name] = Topic(self.participant, name, cls)
            return self._topics[name]

    def manifests(self, timeout: float = 2.0, until=None):
        """Every gateway's newest manifest, by gateway name; waits up to `timeout` s (or until `until(m)`)."""
        deadline = time.monotonic() + timeout
        while True:
            self.take_manifests()
            if until is not None and until(self._manifests):
                break
            if time.monotonic() >= deadline:
                break
            time.sleep(0.02)
        return dict(self._manifests)

    def take_manifests(self) -> bool:
        """Takes what the registry received (no wait); true if a manifest arrived."""
        got = False
        for m in self._registry.take(N=256):
            if isinstance(m, msgs.Manifest):
                self._manifests[m.gateway] = m
                self._writer_of[m.gateway] = m.sample_info.publication_handle & 0xFFFFFFFFFFFFFFFF
                got = True
        return got

    def alive(self) -> dict:
        """Liveliness, by gateway name: a gateway is alive while its manifest writer is matched by
        our registry reader. A gateway that exits or vanishes is unmatched (at once, or when its
        participant's lease expires), however quiet its topics were."""
        # The binding gives matched handles signed and SampleInfo's unsigned: compared as uint64.
        matched = {h & 0xFFFFFFFFFFFFFFFF for h in self._registry.get_matched_publications()}
        return {g: h in matched for g, h in self._writer_of.items()}

    def endpoints(self, timeout: float = 2.0):
        return [e for m in self.manifests(timeout).values() for e in m.endpoints]

    def find(self, topic: str, timeout: float = 5.0):
        """The endpoint serving `topic`, from the registry."""
        found = self.manifests(timeout, until=lambda ms: any(e.topic == topic for m in ms.values()
                                                              for e in m.endpoints))
        for m in found.values():
            for e in m.endpoints:
                if e.topic == topic:
                    return e
        raise LookupError(f"no gateway serves {topic}")

    def reader(self, topic: str, reliable: bool = False, depth: int = 16):
        e = self.find(topic)
        return self.reader_for(e, reliable, depth)

    def reader_for(self, e, reliable: bool = False, depth: int = 16, display: bool = False):
        """A reader of endpoint `e`'s topic, with the QoS reader_qos() gives it; with `display`, of
        its display stream instead when the gateway publishes one (display_topic())."""
        cls = msgs.BY_DDS_NAME[e.dds_type]
        qos = reader_qos(e, depth)
        if reliable and not latched(e):
            qos = Qos(Policy.Reliability.Reliable(0), Policy.History.KeepLast(depth), XCDR1)
        topic = display_topic(e) if display else ""
        return DataReader(self.participant, self._topic(topic or e.topic, cls), qos=qos)

    def error_reader(self, component: str, depth: int = 16):
        """Commands the gateway refused for `component` (crtk_msgs/StringStamped on rt/<component>/error)."""
        return DataReader(self.participant, self._topic(f"rt/{component}/error", msgs.StringStamped),
                          qos=error_qos(depth))

    @staticmethod
    def wait_matched(reader, timeout: float = 5.0) -> bool:
        """Waits until `reader` has matched a writer (discovery), so that nothing sent next is missed."""
        deadline = time.monotonic() + timeout
        while not reader.get_matched_publications():
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.005)
        return True

    def read(self, topic: str, timeout: float = 5.0):
        """The next sample published on `topic` (state or event)."""
        r = self.reader(topic)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for s in r.take(N=1):
                return s
            time.sleep(0.002)
        raise TimeoutError(f"nothing on {topic} within {timeout} s")

    def writer(self, topic: str):
        return self.writer_for(self.find(topic))

    def writer_for(self, e):
        """A writer of command endpoint `e` (write or void) and its message class."""
        topic = e.topic
        if e.kind not in ("write", "void"):
            raise ValueError(f"{topic} is a {e.kind}, not a command")
        cls = msgs.BY_DDS_NAME[e.dds_type]
        return DataWriter(self.participant, self._topic(topic, cls),
                          qos=Qos(Policy.Reliability.Reliable(10**9), Policy.History.KeepLast(16), XCDR1)), cls

    def send(self, topic: str, sample, wait_for_gateway: float = 5.0):
        """Sends one command, after the gateway's reader has matched (so it is not lost)."""
        w, _ = self.writer(topic)
        deadline = time.monotonic() + wait_for_gateway
        while not w.get_matched_subscriptions() and time.monotonic() < deadline:
            time.sleep(0.01)
        w.write(sample)
        return w
