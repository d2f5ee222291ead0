"""Our outputs read by the peer libraries researchers use, compared with what the recording says they hold.

* **Ultralytics** (YOLO): ``check_det_dataset`` accepts ``data.yaml``, ``YOLODataset`` reads every image's class
  ids and normalised ``x y w h``, and a model built from ``yolov8n.yaml`` trains and validates one epoch on CPU
  with every box counted; a scenario, agent or camera folder named ``images`` keeps its labels (Ultralytics finds
  a label by replacing the *last* ``images`` folder of the image path with ``labels``).
* **torchvision**: ``datasets.Kitti`` reads the KITTI ``image_2``/``label_2`` of each agent (and its v2 wrapper the
  boxes), ``datasets.CocoDetection`` with the v2 wrapper the COCO boxes, categories and RLE masks.
* **Foxglove's official schemas** (``foxglove-schemas-protobuf``): every ``foxglove.*`` schema embedded in a
  recording has the official messages (fields, numbers, types, labels, nested types, enums), and every message
  decodes with the official compiled classes to exactly what ``mcap_protobuf``'s dynamic decoding of our
  descriptors gives, with no unknown field and the same bytes re-encoded.
* **supervision**: ``DetectionDataset.from_coco`` (boxes, classes, masks) and ``from_yolo`` (one camera folder).
* **pypcd4**: the OPV2V ``.pcd`` clouds (points and the intensity in the red byte of ``rgb``), the empty one too.

Every expectation comes from the recording (annotations, world state, ``/tf``, images, point clouds) and the
documented conventions (docs/exports.md), never from the exporters' code. Ultralytics runs offline: no settings in
the home folder, its font found locally, and every name look-up other than the loopback's refused.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import io
import math
import os
import shutil
import socket
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mmusv.classes import SemanticClass, class_name
from mmusv.export import convert
from mmusv.recording import decode_image, decode_point_cloud, frame_messages, read_info, topics
from recorded_boxes import recorded
from scipy.spatial.transform import Rotation

CLASSES = [int(c) for c in SemanticClass if c != 0]
"""The YOLO class index of an mmusv class is its position here (docs/exports.md: every class but ``none``)."""


def need(module: str, package: str) -> None:
    """Skip when the peer ``package`` (in the ``test`` extra) is not installed."""
    if importlib.util.find_spec(module) is None:
        pytest.skip(f"{package} is not installed (pip install -e '.[test]' installs it)")


@contextlib.contextmanager
def quiet_pycocotools() -> Iterator[None]:
    """pycocotools prints while loading, and its RLE decoder's ``__array__`` predates numpy 2's ``copy`` keyword
    (a DeprecationWarning from pycocotools 2.0.11, not ours to fix)."""
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.filterwarnings("ignore", category=DeprecationWarning, message=".*copy keyword")
        yield


# ---------------------------------------------------------------------------------------------------------------
# what the recording says the image datasets hold


def image_boxes(rec: Path, frames: int) -> dict[str, list[dict[str, Any]]]:
    """Per image ``<scenario>/<agent>/<camera>/<frame:06d>``: the recorded 2D boxes with a visible pixel (the default
    filters), each with its class, instance id, pixel box and the image size. The pixel box is the default
    ``--box visible`` (docs/exports.md): the tight box, in pixel edges, of the instance image's pixels equal to the
    vessel's instance id (it was the recorded projected box while that was the only box the exports wrote), from
    ``recorded_boxes.recorded``'s walk of the instance images."""
    return {
        f"{rec.stem}/{agent}/{camera}/{k:06d}": [
            {
                "class": e["class"],
                "instance": e["instance"],
                "xyxy": np.array(e["visible"], dtype=np.float64),
                "size": e["size"],
                "agent": agent,
                "camera": camera,
                "frame": k,
            }
            for e in per.values()
        ]
        for (agent, camera, k), per in recorded(rec, frames).items()
    }


def documented_yolo_path(key: str) -> str:
    """Where docs/exports.md puts an image key in the YOLO export: a folder named ``images``, ``images_``, … gets
    one more ``_``."""
    return "/".join(p + "_" if p.rstrip("_") == "images" else p for p in key.split("/"))


def yolo_rows(boxes: list[dict[str, Any]]) -> np.ndarray:
    """``(n, 5)``: YOLO class index and normalised ``x_centre y_centre width height``, sorted."""
    rows = []
    for b in boxes:
        (x0, y0, x1, y1), (w, h) = b["xyxy"], b["size"]
        rows.append([CLASSES.index(b["class"]), (x0 + x1) / 2 / w, (y0 + y1) / 2 / h, (x1 - x0) / w, (y1 - y0) / h])
    return np.array(sorted(rows), dtype=np.float64).reshape(-1, 5)


# ---------------------------------------------------------------------------------------------------------------
# Ultralytics


@contextlib.contextmanager
def no_network() -> Iterator[None]:
    """Every host name look-up other than the loopback's fails while in the block."""
    real = socket.getaddrinfo

    def local_only(host: Any, *args: Any, **kwargs: Any) -> Any:
        if host not in ("localhost", "127.0.0.1", "::1", None):
            raise OSError(f"test_peer_readers: no network ({host})")
        return real(host, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(socket, "getaddrinfo", local_only)
        yield


@pytest.fixture(scope="module")
def ultralytics_env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    """Ultralytics imported offline with its settings in a temporary folder and the font it checks for found
    there (it would download Arial.ttf); what its import changes in the process is put back afterwards."""
    need("ultralytics", "ultralytics")
    import cv2
    import matplotlib
    import torch

    cfg = tmp_path_factory.mktemp("ultralytics_cfg")
    (cfg / "Ultralytics").mkdir()
    shutil.copy(
        Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf", cfg / "Ultralytics" / "Arial.ttf"
    )
    env, np_print = dict(os.environ), np.get_printoptions()
    cv2_threads, torch_threads, torch_save = cv2.getNumThreads(), torch.get_num_threads(), torch.save
    os.environ.update(YOLO_OFFLINE="1", YOLO_CONFIG_DIR=str(cfg), YOLO_VERBOSE="False")
    try:
        with no_network():
            ul = importlib.import_module("ultralytics")
        from ultralytics.utils import SETTINGS

        off = ("sync", "raytune", "mlflow", "comet", "clearml", "dvc", "tensorboard", "wandb")
        SETTINGS.update({k: False for k in off if k in SETTINGS})
        yield ul
    finally:
        os.environ.clear()
        os.environ.update(env)
        np.set_printoptions(**np_print)
        torch.set_printoptions(profile="default")
        cv2.setNumThreads(cv2_threads)
        torch.set_num_threads(torch_threads)
        torch.save = torch_save


@pytest.fixture()
def offline() -> Iterator[None]:
    """No network for the test (Ultralytics must not reach out)."""
    with no_network():
        yield


@pytest.fixture(scope="module")
def yolo_port(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("peer_yolo") / "o"
    convert(port_rec, to="yolo", out_dir=out, splits=None)
    return out


def image_sizes(rec: Path) -> dict[str, tuple[int, int]]:
    """Per image key but the frame (``<scenario>/<agent>/<camera>``): the camera's width and height."""
    return {f"{rec.stem}/{a.id}/{n}": (c.width, c.height) for a in read_info(rec).agents for n, c in a.cameras.items()}


def ultralytics_data(out: Path) -> dict[str, Any]:
    """``out``'s ``data.yaml`` as Ultralytics' ``check_det_dataset`` checks and resolves it."""
    from ultralytics.data.utils import check_det_dataset

    data: dict[str, Any] = check_det_dataset(str(out / "data.yaml"))
    assert data["nc"] == len(CLASSES)
    assert data["names"] == {i: class_name(c) for i, c in enumerate(CLASSES)}
    return data


def ultralytics_reads(
    data: dict[str, Any], folder: Path, want: dict[str, list[dict[str, Any]]], sizes: dict[str, tuple[int, int]]
) -> None:
    """Ultralytics' ``YOLODataset`` over the image ``folder`` reads one label entry per image of ``want``, with the
    image's size and exactly ``want``'s boxes (class index, normalised ``x y w h``)."""
    from ultralytics.data.dataset import YOLODataset

    ds = YOLODataset(img_path=str(folder), data=data, task="detect", imgsz=160, augment=False)
    root = folder.resolve()
    got = {str(Path(lab["im_file"]).resolve().relative_to(root).with_suffix("")): lab for lab in ds.labels}
    assert len(got) == len(ds.labels) == len(want)
    for key, boxes_want in want.items():
        lab = got[documented_yolo_path(key) if documented_yolo_path(key) in got else key]
        w, h = sizes[key.rsplit("/", 1)[0]]
        assert lab["shape"] == (h, w) and lab["normalized"] and lab["bbox_format"] == "xywh"
        rows = np.column_stack([lab["cls"].reshape(-1), lab["bboxes"].reshape(-1, 4)]).astype(np.float64)
        rows = np.array(sorted(rows.tolist())).reshape(-1, 5)
        exp = yolo_rows(boxes_want)
        assert rows.shape == exp.shape, (key, rows, exp)
        np.testing.assert_array_equal(rows[:, 0], exp[:, 0])
        np.testing.assert_allclose(rows[:, 1:], exp[:, 1:], atol=1e-6)  # 6 decimals, float32


def test_ultralytics_reads_every_yolo_label(
    ultralytics_env: Any, offline: None, yolo_port: Path, port_rec: Path
) -> None:
    """``check_det_dataset`` accepts ``data.yaml`` (``train`` = ``val`` = ``images/all`` without a split) and
    ``YOLODataset`` reads every image's boxes as recorded."""
    want = image_boxes(port_rec, 3)
    assert len(want) == 36 and sum(len(b) for b in want.values()) >= 10
    data = ultralytics_data(yolo_port)
    assert Path(data["train"]) == Path(data["val"]) == (yolo_port / "images" / "all").resolve()
    assert "test" not in data or data["test"] is None
    ultralytics_reads(data, yolo_port / "images" / "all", want, image_sizes(port_rec))


def test_ultralytics_reads_every_split(
    ultralytics_env: Any, offline: None, many_recs: list[Path], tmp_path: Path
) -> None:
    """With a split, ``train``/``val``/``test`` are the ``train``/``validate``/``test`` folders; each holds whole
    recordings, and Ultralytics reads their boxes as recorded."""
    out = tmp_path / "yolo"
    convert(many_recs, to="yolo", out_dir=out)
    data = ultralytics_data(out)
    seen: list[str] = []
    for key, split in (("train", "train"), ("val", "validate"), ("test", "test")):
        folder = out / "images" / split
        assert Path(data[key]) == folder.resolve()
        recs = [r for r in many_recs if (folder / r.stem).is_dir()]
        assert recs, split
        seen += [r.stem for r in recs]
        want = {k: v for r in recs for k, v in image_boxes(r, 2).items()}
        ultralytics_reads(data, folder, want, {k: v for r in recs for k, v in image_sizes(r).items()})
    assert sorted(seen) == sorted(r.stem for r in many_recs)


def test_ultralytics_keeps_the_labels_of_a_folder_named_images(
    ultralytics_env: Any, offline: None, make_coop: Any, tmp_path: Path
) -> None:
    """An agent named ``images`` in a scenario named ``labels``: Ultralytics reads its images' boxes (it looks for
    an image's labels by replacing the last ``images`` folder of its path with ``labels``)."""
    from mmusv.acquire import run

    cfg = make_coop(name="labels")
    cfg["acquisition"] = {"frequency_hz": 5, "frames": 1}
    for v in cfg["vessels"]:
        if v["id"] == "usv_a":
            v["id"] = "images"
    rec = Path(run(cfg, out_dir=tmp_path / "rec").recording)
    out = tmp_path / "yolo"
    convert(rec, to="yolo", out_dir=out, splits=None)
    want = image_boxes(rec, 1)
    assert sum(len(b) for k, b in want.items() if k.startswith("labels/images/")) >= 1
    ultralytics_reads(ultralytics_data(out), out / "images" / "all", want, image_sizes(rec))
    assert (out / "images" / "all" / "labels" / "images_" / "front" / "000000.png").is_file()


def test_ultralytics_trains_and_validates_one_epoch(
    ultralytics_env: Any, offline: None, yolo_port: Path, port_rec: Path, tmp_path: Path
) -> None:
    """A YOLOv8n built from its yaml (no weights to download) trains one epoch at 64 px on CPU and validates:
    the validator counts every recorded box under its class."""
    from ultralytics import YOLO

    want = image_boxes(port_rec, 3)
    counts = np.bincount([yolo_rows([b])[0, 0].astype(int) for bs in want.values() for b in bs], minlength=10)
    model = YOLO("yolov8n.yaml")
    model.train(
        data=str(yolo_port / "data.yaml"),
        epochs=1,
        imgsz=64,
        batch=12,
        workers=0,
        device="cpu",
        plots=False,
        amp=False,
        deterministic=False,
        project=str(tmp_path / "runs"),
        name="train",
        verbose=False,
    )
    trainer = model.trainer
    assert trainer is not None and trainer.epoch == 0
    losses = trainer.tloss.values() if isinstance(trainer.tloss, dict) else trainer.tloss.reshape(-1).tolist()
    assert losses and all(math.isfinite(float(v)) for v in losses), trainer.tloss
    assert (tmp_path / "runs" / "train" / "weights" / "last.pt").is_file()
    metrics = trainer.validator.metrics
    np.testing.assert_array_equal(metrics.nt_per_class, counts)
    assert metrics.nt_per_class[CLASSES.index(SemanticClass.VESSEL)] >= 10


# ---------------------------------------------------------------------------------------------------------------
# torchvision


def pose(t: Any) -> np.ndarray:
    """The 4×4 matrix of a foxglove ``FrameTransform`` (the child's pose in the parent)."""
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w]).as_matrix()
    m[:3, 3] = [t.translation.x, t.translation.y, t.translation.z]
    return m


def wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def kitti_objects(rec: Path, agent: str, k: int) -> list[dict[str, Any]]:
    """The KITTI objects of ``agent``'s frame ``k`` from the recording: every non-USV vessel of the LiDAR
    annotations within 200 m (the default range), in KITTI's camera conventions (docs/exports.md) with the camera
    the front camera's optical frame of ``/tf``: bottom-centre location of the upright box (the box centre h/2 down
    the camera's y axis, where a reader adding h/2 back finds the centre), ``rotation_y`` about the camera's y axis
    (the box's x axis is ``(cos ry, 0, -sin ry)``), dimensions ``h w l``, the front camera's 2D box (``0 0 0 0``
    with occluded 3 and truncated 1 when it has none; ``0 0 0 0`` with occluded 3 and its truncation when no pixel of
    it is seen)."""
    msgs = frame_messages(rec, k)
    world = {v.id: v for v in msgs[topics.WORLD_STATE].vessels}
    tf = {(t.parent_frame_id, t.child_frame_id): t for t in msgs[topics.TF].transforms}
    velo_to_cam = np.linalg.inv(pose(tf[(agent, f"{agent}/camera/front")])) @ pose(tf[(agent, f"{agent}/lidar")])
    ann = msgs[topics.agent_annotations(agent)]
    boxes2d = {b.target_id: b for b in ann.boxes_camera if b.camera == "front"}
    out = []
    for b in ann.boxes_lidar:
        if world[b.target_id].role == "usv" or math.hypot(b.center[0], b.center[1]) > 200.0:
            continue
        length, width, height = b.size
        rot = Rotation.from_quat(list(b.rotation)).as_matrix()
        loc = velo_to_cam[:3, :3] @ np.asarray(b.center) + velo_to_cam[:3, 3] + [0.0, height / 2, 0.0]
        x_axis = velo_to_cam[:3, :3] @ rot[:, 0]
        ry = math.atan2(-x_axis[2], x_axis[0])
        b2 = boxes2d.get(b.target_id)
        cut = 1.0 if b2 is None else b2.truncation  # out of the image: wholly truncated
        if b2 is not None and b2.visible_pixels == 0:  # in view, no pixel seen (hidden wholly): KITTI's "unknown"
            b2 = None
        occ = 3 if b2 is None else 0 if b2.occlusion < 0.25 else 1 if b2.occlusion < 0.6 else 2
        out.append(
            {
                "type": class_name(world[b.target_id].semantic_class).capitalize(),
                "truncated": cut,
                "occluded": occ,
                "alpha": wrap(ry - math.atan2(loc[0], loc[2])),
                "bbox": [0.0] * 4 if b2 is None else [b2.x_min, b2.y_min, b2.x_max, b2.y_max],
                "dimensions": [height, width, length],
                "location": loc.tolist(),
                "rotation_y": ry,
            }
        )
    return out


@pytest.fixture(scope="module")
def kitti_coop(coop_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("peer_kitti") / "o"
    convert(coop_rec, to="kitti", out_dir=out, splits=None)
    return out / coop_rec.stem


def test_torchvision_kitti_reads_the_kitti_export(kitti_coop: Path, coop_rec: Path, tmp_path: Path) -> None:
    """``torchvision.datasets.Kitti`` (``<root>/Kitti/raw/training/{image_2,label_2}``, here a link to an agent's
    folder) reads each agent's images and labels: type, truncation, occlusion level, alpha, 2D box, dimensions,
    location and ``rotation_y`` as the recording has them, to the labels' 2 decimals; its v2 wrapper gives the
    same boxes as XYXY on the image's canvas."""
    need("torchvision", "torchvision")
    from torchvision.datasets import Kitti, wrap_dataset_for_transforms_v2
    from torchvision.tv_tensors import BoundingBoxFormat

    info = read_info(coop_rec)
    n = 0
    for a in info.agents:
        root = tmp_path / a.id
        (root / "Kitti" / "raw").mkdir(parents=True)
        (root / "Kitti" / "raw" / "training").symlink_to(kitti_coop / str(1000 + a.index))
        ds = Kitti(str(root), train=True)
        assert sorted(Path(p).name for p in ds.images) == [f"{k:06d}.png" for k in range(3)]
        wrapped = wrap_dataset_for_transforms_v2(ds, target_keys={"boxes", "type"})
        for i in range(len(ds)):
            image, target = ds[i]
            image.close()
            assert image.size == (a.cameras["front"].width, a.cameras["front"].height)
            k = int(Path(ds.images[i]).stem)
            want = kitti_objects(coop_rec, a.id, k)
            objects = [obj for obj in target if obj["type"] != "DontCare"]  # regions to ignore, as KITTI's own
            assert len(objects) == len(want) == 2, (a.id, k, target)
            for obj in objects:
                exp = min(want, key=lambda w: float(np.linalg.norm(np.subtract(w["location"], obj["location"]))))
                assert obj["type"] == exp["type"] == "Vessel" and obj["occluded"] == exp["occluded"]
                assert obj["truncated"] == pytest.approx(exp["truncated"], abs=0.005)
                np.testing.assert_allclose(obj["bbox"], exp["bbox"], atol=0.006)
                np.testing.assert_allclose(obj["dimensions"], exp["dimensions"], atol=0.006)
                np.testing.assert_allclose(obj["location"], exp["location"], atol=0.006)
                assert wrap(obj["rotation_y"] - exp["rotation_y"]) == pytest.approx(0.0, abs=0.006)
                assert wrap(obj["alpha"] - exp["alpha"]) == pytest.approx(0.0, abs=0.006)
                n += 1
            image, t2 = wrapped[i]
            image.close()
            assert t2["boxes"].format == BoundingBoxFormat.XYXY
            assert tuple(t2["boxes"].canvas_size) == (image.height, image.width)
            np.testing.assert_allclose(t2["boxes"].numpy(), [o["bbox"] for o in target], atol=1e-4)
            assert t2["type"] == [o["type"] for o in target]
    assert n == 12  # 2 agents x 3 frames x (tug, speedboat)


@pytest.fixture(scope="module")
def coco_port(port_rec: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("peer_coco") / "o"
    convert(port_rec, to="coco", out_dir=out, splits=None)
    return out


def instance_masks(rec: Path, boxes: list[dict[str, Any]]) -> np.ndarray:
    """``(n, H, W)`` uint8: the recorded instance image's pixels of each box's vessel."""
    if not boxes:
        return np.zeros((0, 0, 0), np.uint8)
    b = boxes[0]
    inst = decode_image(frame_messages(rec, b["frame"])[topics.camera(b["agent"], b["camera"], kind="instance")])
    return np.stack([(inst == x["instance"]).astype(np.uint8) for x in boxes])


def test_torchvision_coco_detection_reads_boxes_classes_and_masks(coco_port: Path, port_rec: Path) -> None:
    """``torchvision.datasets.CocoDetection`` with its v2 wrapper: XYXY boxes, category ids (the mmusv class ids)
    and the RLE masks decoded to the recorded instance images."""
    need("torchvision", "torchvision")
    need("pycocotools", "pycocotools")
    from torchvision.datasets import CocoDetection, wrap_dataset_for_transforms_v2

    want = image_boxes(port_rec, 3)
    with quiet_pycocotools():
        ds = CocoDetection(str(coco_port / "images" / "all"), str(coco_port / "annotations" / "instances_all.json"))
    wrapped = wrap_dataset_for_transforms_v2(ds, target_keys={"image_id", "boxes", "labels", "masks"})
    assert len(ds) == len(want) == 36
    n = 0
    for i in range(len(ds)):
        key = str(Path(ds.coco.imgs[ds.ids[i]]["file_name"]).with_suffix(""))
        exp = sorted(want[key], key=lambda b: b["xyxy"].tolist())
        with quiet_pycocotools():
            image, target = wrapped[i]
        w, h = exp[0]["size"] if exp else (image.width, image.height)
        assert (image.width, image.height) == (w, h)
        if not exp:
            assert "boxes" not in target
            continue
        order = np.lexsort(target["boxes"].numpy().T[::-1])
        np.testing.assert_allclose(target["boxes"].numpy()[order], [b["xyxy"] for b in exp], atol=2e-3)
        assert target["labels"].numpy()[order].tolist() == [b["class"] for b in exp]
        np.testing.assert_array_equal(target["masks"].numpy()[order], instance_masks(port_rec, exp))
        n += len(exp)
    assert n == sum(len(b) for b in want.values()) >= 10


# ---------------------------------------------------------------------------------------------------------------
# Foxglove's official schemas


def official_module(schema: str) -> Any:
    """The compiled module of ``foxglove.X`` (``foxglove_schemas_protobuf.X_pb2``)."""
    return importlib.import_module(f"foxglove_schemas_protobuf.{schema.split('.', 1)[1]}_pb2")


def test_foxglove_schemas_are_the_official_ones(coop_rec: Path) -> None:
    """Every ``foxglove/*.proto`` file in the descriptor sets embedded in the recording equals the official one
    (package, dependencies, messages with their fields — name, number, label, type, type name, oneof — nested
    types, enums), and each field's ``json_name`` is the one protobuf derives."""
    need("foxglove_schemas_protobuf", "foxglove-schemas-protobuf")
    from google.protobuf import descriptor_pb2
    from mcap.reader import make_reader

    with coop_rec.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    files: dict[str, Any] = {}
    names = set()
    for schema in summary.schemas.values():
        if not schema.name.startswith("foxglove."):
            continue
        names.add(schema.name)
        assert schema.encoding == "protobuf"
        for fd in descriptor_pb2.FileDescriptorSet.FromString(schema.data).file:
            assert files.setdefault(fd.name, fd) == fd, fd.name  # one definition of each file in the recording
    assert names == {
        "foxglove.PointCloud",
        "foxglove.RawImage",
        "foxglove.CompressedImage",
        "foxglove.FrameTransforms",
        "foxglove.SceneUpdate",
        "foxglove.CameraCalibration",
        "foxglove.ImageAnnotations",
    }
    checked = 0
    for name, ours in sorted(files.items()):
        if not name.startswith("foxglove/"):
            continue
        module = official_module("foxglove." + Path(name).stem)
        official = descriptor_pb2.FileDescriptorProto()
        module.DESCRIPTOR.CopyToProto(official)  # CopyToProto leaves json_name out
        mine = descriptor_pb2.FileDescriptorProto()
        mine.CopyFrom(ours)
        json_names: dict[str, str] = {}

        def strip(msg: Any, prefix: str, into: dict[str, str]) -> None:
            for fld in msg.field:
                into[f"{prefix}{msg.name}.{fld.name}"] = fld.json_name
                fld.ClearField("json_name")
            for nested in msg.nested_type:
                strip(nested, f"{prefix}{msg.name}.", into)

        for msg in mine.message_type:
            strip(msg, "", json_names)
        assert mine == official, f"{name}:\nours:\n{mine}\nofficial:\n{official}"
        for msg in module.DESCRIPTOR.message_types_by_name.values():
            for fld in msg.fields:
                assert json_names[f"{msg.name}.{fld.name}"] == fld.json_name, (name, fld.full_name)
                checked += 1
    assert checked >= 50


def test_foxglove_official_classes_decode_every_message(coop_rec: Path) -> None:
    """Every ``foxglove.*`` message of the recording decodes with the official compiled class to the same fields
    as ``mcap_protobuf``'s dynamic decoding of the embedded descriptors, leaves no unknown field and re-encodes to
    the recorded bytes."""
    need("foxglove_schemas_protobuf", "foxglove-schemas-protobuf")
    from google.protobuf import json_format
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory

    def fields(m: Any) -> dict[str, Any]:
        out: dict[str, Any] = json_format.MessageToDict(
            m, preserving_proto_field_name=True, always_print_fields_with_no_presence=True
        )
        return out

    counts: dict[str, int] = {}
    with coop_rec.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        for schema, channel, message, dynamic in reader.iter_decoded_messages():
            assert schema is not None
            if not schema.name.startswith("foxglove."):
                continue
            cls = getattr(official_module(schema.name), schema.name.split(".", 1)[1])
            official = cls.FromString(message.data)
            assert fields(official) == fields(dynamic), (channel.topic, message.sequence)
            known = cls()
            known.CopyFrom(official)
            known.DiscardUnknownFields()
            assert known.SerializeToString(deterministic=True) == message.data, (channel.topic, message.sequence)
            counts[schema.name] = counts.get(schema.name, 0) + 1
    # 3 frames: per USV (2) a cloud, 4 cameras x (rgb, semantic, instance PNG + depth raw, calibration, 2D boxes),
    # top view (3 PNG), the radar PPI (PNG), boxes; /tf
    assert counts == {
        "foxglove.PointCloud": 12,
        "foxglove.CompressedImage": 96,
        "foxglove.RawImage": 24,
        "foxglove.SceneUpdate": 6,
        "foxglove.FrameTransforms": 3,
        "foxglove.CameraCalibration": 24,
        "foxglove.ImageAnnotations": 24,
    }


# ---------------------------------------------------------------------------------------------------------------
# supervision


def test_supervision_reads_the_coco_and_yolo_exports(coco_port: Path, yolo_port: Path, port_rec: Path) -> None:
    """``DetectionDataset.from_coco`` over the whole split (boxes, class names, masks) and ``from_yolo`` over one
    camera folder (it reads a flat folder: ``images_directory_path`` and ``annotations_directory_path`` are
    ``images/<split>/<scenario>/<agent>/<camera>`` and the same under ``labels``)."""
    need("supervision", "supervision")
    import supervision as sv

    want = image_boxes(port_rec, 3)
    names = [class_name(c) for c in CLASSES]
    with quiet_pycocotools():
        coco = sv.DetectionDataset.from_coco(
            images_directory_path=str(coco_port / "images" / "all"),
            annotations_path=str(coco_port / "annotations" / "instances_all.json"),
        )
    assert coco.classes == names and len(coco) == len(want)
    root = (coco_port / "images" / "all").resolve()
    n = 0
    for path, image, det in coco:
        key = str(Path(path).resolve().relative_to(root).with_suffix(""))
        exp = sorted(want[key], key=lambda b: b["xyxy"].tolist())
        if exp:
            assert image.shape == (exp[0]["size"][1], exp[0]["size"][0], 3)
        order = np.lexsort(det.xyxy.T[::-1]) if len(det) else np.zeros(0, int)
        np.testing.assert_allclose(
            det.xyxy[order].reshape(-1, 4), [b["xyxy"] for b in exp] or np.zeros((0, 4)), atol=2e-3
        )
        assert [names[c] for c in det.class_id[order]] == [class_name(b["class"]) for b in exp]
        if exp:
            np.testing.assert_array_equal(det.mask[order], instance_masks(port_rec, exp).astype(bool))
        n += len(exp)
    assert n == sum(len(b) for b in want.values())

    leaf = f"{port_rec.stem}/usv_1/front"
    yolo = sv.DetectionDataset.from_yolo(
        images_directory_path=str(yolo_port / "images" / "all" / leaf),
        annotations_directory_path=str(yolo_port / "labels" / "all" / leaf),
        data_yaml_path=str(yolo_port / "data.yaml"),
    )
    assert yolo.classes == names and len(yolo) == 3
    m = 0
    for path, _, det in yolo:
        exp = sorted(want[f"{leaf}/{Path(path).stem}"], key=lambda b: b["xyxy"].tolist())
        order = np.lexsort(det.xyxy.T[::-1]) if len(det) else np.zeros(0, int)
        # 6 decimals of the image size: 1e-4 px
        np.testing.assert_allclose(
            det.xyxy[order].reshape(-1, 4), [b["xyxy"] for b in exp] or np.zeros((0, 4)), atol=1e-3
        )
        assert [names[c] for c in det.class_id[order]] == [class_name(b["class"]) for b in exp]
        m += len(exp)
    assert m >= 1


# ---------------------------------------------------------------------------------------------------------------
# pypcd4


def test_pypcd4_reads_the_opv2v_clouds(coop_rec: Path, tmp_path: Path) -> None:
    """pypcd4 reads every OPV2V ``.pcd``: fields ``x y z rgb`` (float32, float32, float32, uint32), the recorded
    points with y mirrored (CARLA's left-handed frame) to 0.1 mm, the intensity in the red byte of ``rgb``; and a
    scan without a point as an empty cloud."""
    need("pypcd4", "pypcd4")
    from mmusv.export.pcd import pcd_bytes
    from pypcd4 import PointCloud

    out = tmp_path / "opv2v"
    convert(coop_rec, to="opv2v", out_dir=out, splits=None)
    info = read_info(coop_rec)
    n = 0
    for k in range(3):
        msgs = frame_messages(coop_rec, k)
        for a in info.agents:
            cloud = decode_point_cloud(msgs[topics.lidar(a.id)])
            pc = PointCloud.from_path(out / coop_rec.stem / str(1000 + a.index) / f"{k:06d}.pcd")
            assert pc.fields == ("x", "y", "z", "rgb") and pc.points == len(cloud["x"]) > 100
            assert pc.types == (np.float32, np.float32, np.float32, np.uint32)
            arr = pc.numpy()
            want = np.column_stack([cloud["x"], -np.asarray(cloud["y"]), cloud["z"]])
            np.testing.assert_allclose(arr[:, :3], want, atol=6e-5)
            rgb = arr[:, 3].astype(np.uint32)
            assert not (rgb & 0xFFFF).any()
            np.testing.assert_allclose((rgb >> 16) / 255.0, np.clip(cloud["intensity"], 0, 1), atol=0.5 / 255 + 1e-9)
            n += 1
    assert n == 6
    (tmp_path / "empty.pcd").write_bytes(pcd_bytes(np.zeros((0, 3)), np.zeros(0)))
    empty = PointCloud.from_path(tmp_path / "empty.pcd")
    assert empty.points == 0 and empty.numpy().shape == (0, 4)
