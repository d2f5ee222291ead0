"""The cooperative detection benchmark (Tables III and IV of the paper): no, late and early fusion of LiDAR
detections between USVs, scored like OpenCOOD; fixed delay and pose noise for the robustness study.

Modules: :mod:`.evaluate` (BEV IoU, matching, AP), :mod:`.detector` (the training-free baseline and the detector
interface), :mod:`.fusion` (no / late / early fusion), :mod:`.data` (recordings and OPV2V folders),
:mod:`.robustness` (delay and pose-noise settings), :mod:`.study` (the two studies and their outputs).
"""
