"""mmusv.learn: the paper's learned detector, PointPillars (Lang et al., CVPR 2019) with a CenterPoint head
(Yin et al., CVPR 2021), trained on mmusv data, for no, late, early and intermediate fusion.

An optional extra (``pip install .[learn]``, PyTorch). The training core (:mod:`~mmusv.learn.pillars`,
:mod:`~mmusv.learn.backbone`, :mod:`~mmusv.learn.head`, :mod:`~mmusv.learn.targets`,
:mod:`~mmusv.learn.augment`, :mod:`~mmusv.learn.model`, :mod:`~mmusv.learn.train`) needs only torch and numpy,
so a tensor cache (:mod:`~mmusv.learn.cache`, built from the detection study's own dataset code) trains on a
machine without mmusv's native extension (``scripts/learn_train.py``). The detection study takes a trained model
through :mod:`~mmusv.learn.detector`.

Nothing is imported here: ``import mmusv.learn`` must not pull in torch.
"""

from __future__ import annotations

__all__: list[str] = []
