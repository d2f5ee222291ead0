"""Skip mmusv.learn's tests where the learn extra (PyTorch) is not installed; run torch on one thread (on a
machine other jobs share, spinning OpenMP threads made a 2-thread training step 30x slower than a 1-thread one)."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")
torch.set_num_threads(1)
