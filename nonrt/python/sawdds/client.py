"""List a sawrt system's components, read their state and send them commands, over Cyclone DDS.

Loopback only unless CYCLONEDDS_URI says otherwise: the configuration below restricts Cyclone DDS
to interface ``lo`` with unicast discovery (lo has no multicast), finding Fast DDS participants at
their well-known ports.
"""
import os
import time

LOOPBACK_URI = (
    "<CycloneDDS><Domain Id='any'><General><Interfaces><NetworkInterface name='lo'/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"
    "<Peers><Peer address='127.0.0.1'/></Peers></Discovery></Domain></CycloneDDS>"
)
os.environ.setdefault("CYCLONEDDS_URI", LOOPBACK_URI)

from cyclonedds.core import Policy, Qos  # noqa: E402  (after CYCLONEDDS_URI)
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402

from . import msgs  # noqa: E402

XCDR1 = Policy.DataRepresentation(use_cdrv0_representation=True)


class Client:
    def __init__(self, domain: int = 0):
        self.participant = DomainParticipant(domain)
        self._topics = {}
        self._registry = DataReader(
            self.participant,
            self._topic("rt/saw/manifest", msgs.Manifest),
            qos=Qos(Policy.Reliability.Reliable(0), Policy.Durability.TransientLocal, Policy.History.KeepLast(256),
                    XCDR1),
        )
        self._manifests = {}

    def _topic(self, name, cls):
        if name not in self._topics:
            self._topics[name] = Topic(self.participant, name, cls)
        return self._topics[name]

    def manifests(self, timeout: float = 2.0, until=None):
        """Every gateway's newest manifest, by gateway name; waits up to `timeout` s (or until `until(m)`)."""
        deadline = time.monotonic() + timeout
        while True:
            for m in self._registry.take(N=256):
                if isinstance(m, msgs.Manifest):  # not a writer's unregistration (a gateway gone)
                    self._manifests[m.gateway] = m
            if until is not None and until(self._manifests):
                break
            if time.monotonic() >= deadline:
                break
            time.sleep(0.02)
        return dict(self._manifests)

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

    def reader(self, topic: str, reliable: bool = False):
        e = self.find(topic)
        cls = msgs.BY_DDS_NAME[e.dds_type]
        qos = Qos(Policy.Reliability.Reliable(0) if reliable or e.kind.endswith("event")
                  else Policy.Reliability.BestEffort, Policy.History.KeepLast(16), XCDR1)
        return DataReader(self.participant, self._topic(topic, cls), qos=qos)

    def error_reader(self, component: str):
        """Commands the gateway refused for `component` (crtk_msgs/StringStamped on rt/<component>/error)."""
        return DataReader(self.participant, self._topic(f"rt/{component}/error", msgs.StringStamped),
                          qos=Qos(Policy.Reliability.Reliable(0), Policy.History.KeepLast(16), XCDR1))

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
        e = self.find(topic)
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
