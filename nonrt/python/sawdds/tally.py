"""One stream's samples counted within a wall-clock window, by the time their writer wrote them."""
import numpy as np


class Tally:
    """Counts samples whose source time (s, wall clock: the writer's clock, on this machine ours)
    lies in [start, end). Counting by source time rather than by when a sample arrived makes two
    readers that started at different moments count the same samples, whenever each is scheduled.
    What a reader did not get is counted beside: `full_takes`, takes that emptied a full reader
    history (whose oldest samples were overwritten), and, from Cyclone DDS, samples lost between
    writer and reader (a gap in the writer's sequence numbers) and rejected, since `lost0`/`rejected0`."""

    def __init__(self, start: float, end: float, lost0: int = 0, rejected0: int = 0):
        self.start, self.end = start, end
        self.samples = 0
        self.full_takes = 0
        self.lost0, self.rejected0 = lost0, rejected0

    def add(self, times, history_full: bool = False):
        t = np.asarray(times, dtype=float)
        self.samples += int(np.count_nonzero((t >= self.start) & (t < self.end)))
        if history_full:
            self.full_takes += 1

    def summary(self, lost: int = 0, rejected: int = 0) -> dict:
        """{"samples", "full_takes", "lost", "rejected"}; `lost`/`rejected`: the reader's totals now."""
        return {"samples": self.samples, "full_takes": self.full_takes, "lost": lost - self.lost0,
                "rejected": rejected - self.rejected0}
