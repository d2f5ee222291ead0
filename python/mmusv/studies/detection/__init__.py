"""The cooperative detection benchmark (Tables III and IV of the paper): no, late and early fusion of LiDAR
detections between USVs, scored like OpenCOOD; fixed delay and pose noise for the robustness study.

Modules: :mod:`.evaluate` (BEV IoU, matching, AP), :mod:`.detector` (the training-free baseline and the detector
interface), :mod:`.fusion` (no / late / early fusion), :mod:`.data` (recordings and OPV2V folders),
:mod:`.robustness` (delay and pose-noise settings), :mod:`.study` (the two studies and their outputs).
"""

BUNDLED_SPEC = "scenarios/specs/coop_detection.yaml"
"""The bundled detection dataset spec (run from the repository root). Here, not in :mod:`.sources`, because the
``mmusv`` parser names it and every command builds the parser (importing :mod:`.sources` took 0.7 s)."""
