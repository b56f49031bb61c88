"""evray's event stream into tonic and PyTorch: the built-in eye rendered at 346x260 (a DAVIS346's
size), its events cut into 10 ms windows as they arrive, each window made a two-channel frame by
tonic.transforms.ToFrame, and the frames batched by a torch DataLoader. Nothing is written to disk.

    pip install .  &&  pip install tonic==1.7.0 torch==2.15.0
    python examples/python_tonic.py [seconds]

The simulator runs inside the dataset's iterator (num_workers=0: it uses every core itself)."""
import sys

import numpy as np
import tonic.transforms as T
import torch
from torch.utils.data import DataLoader, IterableDataset

import evray

W, H = 346, 260
WINDOW_US = 10_000


class EvrayFrames(IterableDataset):
    """The frames of one run, a window at a time, as the stream gets there."""

    def __init__(self, scene, config):
        self.scene, self.config = scene, config

    def windows(self):
        pending = np.empty(0, evray.EVENT_DTYPE)
        start = None
        for batch in evray.Simulator(self.scene, self.config).stream():
            pending = np.concatenate([pending, batch])
            if start is None and len(pending):
                start = int(pending["t"][0]) // WINDOW_US * WINDOW_US
            # a window is complete once an event past its end has come (events arrive in order)
            while start is not None and len(pending) and pending["t"][-1] >= start + WINDOW_US:
                cut = np.searchsorted(pending["t"], start + WINDOW_US)
                yield pending[:cut]
                pending = pending[cut:]
                start += WINDOW_US
        if len(pending):
            yield pending  # the last, partial window

    def __iter__(self):
        for events in self.windows():
            if len(events) == 0:  # a window nothing happened in
                yield torch.zeros((2, H, W))
            else:
                # one frame of all the window's events (n_time_bins=1 would leave out those at its
                # last timestamp); channel 0 OFF, 1 ON
                frame = T.ToFrame(sensor_size=(W, H, 2), event_count=len(events))(events)[0]
                yield torch.from_numpy(frame.astype(np.float32))  # [2, H, W]


def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 0.2
    scene = evray.demo("eye")
    config = evray.Config(res=(W, H), duration=seconds, sensor="davis346", no_preview=True)
    dataset = EvrayFrames(scene, config)
    loader = DataLoader(dataset, batch_size=8)
    on = off = 0
    for i, frames in enumerate(loader):
        print(f"batch {i}: {tuple(frames.shape)}, {int(frames[:, 1].sum())} ON and "
              f"{int(frames[:, 0].sum())} OFF events")
        on += int(frames[:, 1].sum())
        off += int(frames[:, 0].sum())
    print(f"{on} ON and {off} OFF events in the frames")


if __name__ == "__main__":
    main()
