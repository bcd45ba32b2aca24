"""A Darknet model (``.cfg`` + ``.weights``) as an ONNX graph, built with the ``onnx`` package's helper API.

The graph takes ``images`` (1, 3, size, size: RGB in 0..1, what ``cv2.dnn.blobFromImage`` makes) and gives
``rows`` (N, 5 + classes), the rows OpenCV DNN's Darknet reader gives, in its order (yolo layers in ``.cfg`` order,
each by cell row, cell column, anchor): cx, cy, w, h as fractions of the input, objectness, then each class's score
times the objectness, 0 where that is at or below :data:`SCORE_FLOOR`. So one postprocess serves both runtimes.

Layers: ``convolutional`` (its batch norm folded into the kernel and bias; ``leaky`` or ``linear``), ``shortcut``,
``route``, ``maxpool``, ``upsample``, ``dropout`` (nothing at inference) and ``yolo``: what Yolo-Fastest uses (and
YOLOv3-tiny; only Yolo-Fastest 1.1 is checked against OpenCV DNN). Any other layer, option or value raises
ValueError naming it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

from processors.detection.darknet_cfg import Section, Weights, read_cfg

OPSET = 13
"""ONNX operator set: ``Resize`` and ``Split`` as every ONNX Runtime the ``onnx`` extra allows (>= 1.17) reads them."""
IR_VERSION = 8
"""The file format version ONNX Runtime 1.17 reads (the ``onnx`` package writes a newer one by default)."""
SCORE_FLOOR = 0.2
"""OpenCV's region layer sets a class score at or below this to 0 (its ``thresh``, which its Darknet reader leaves at
the default); the graph does the same, so the two runtimes' rows agree."""
BN_EPSILON = 1e-6
"""Added to the batch norm's variance before its square root, as Darknet and OpenCV's reader do."""
LEAKY_SLOPE = 0.1
"""Darknet's ``leaky`` activation: x for x > 0, else 0.1 x."""
OPTIONS = {
    "convolutional": {"filters", "size", "stride", "pad", "padding", "groups", "batch_normalize", "activation"},
    "shortcut": {"from", "activation"},
    "route": {"layers"},
    "maxpool": {"size", "stride", "padding"},
    "upsample": {"stride"},
}
"""The options each layer may have (another, such as route's ``groups``, changes what it computes); a yolo or dropout
layer's other options are training settings."""


@dataclass(frozen=True)
class _Tensor:
    """A layer's output: its name in the graph and its shape (channels, height, width; batch 1)."""

    name: str
    channels: int
    height: int
    width: int


@dataclass(frozen=True)
class _Rows:
    """A yolo layer's decoded rows: their name in the graph, how many (cells x anchors) and their columns."""

    name: str
    count: int
    columns: int


class _Graph:
    """Nodes and constants, added in order."""

    def __init__(self) -> None:
        self.nodes: list[onnx.NodeProto] = []
        self.constants: list[onnx.TensorProto] = []

    def op(self, op_type: str, inputs: list[str], name: str, outputs: int = 1, **attributes: Any) -> str:
        """Add a node named ``name``; its output is ``name`` (``name_0`` ... when ``outputs`` > 1)."""
        names = [name] if outputs == 1 else [f"{name}_{i}" for i in range(outputs)]
        self.nodes.append(helper.make_node(op_type, inputs, names, name=name, **attributes))
        return name

    def const(self, value: np.ndarray, name: str) -> str:
        self.constants.append(numpy_helper.from_array(value, name))
        return name


def darknet_to_onnx(cfg: Path, weights: Path, size: int) -> onnx.ModelProto:
    """The model of ``cfg`` with the floats of ``weights``, for a ``size`` x ``size`` input (checked by
    ``onnx.checker``).

    Raises:
        ValueError: a layer or option the converter does not support, or weights that do not fit the ``.cfg``.
    """
    sections = read_cfg(cfg)
    graph, floats = _Graph(), Weights(weights)
    channels = sections[0].get_int("channels", 3)
    x = _Tensor("images", channels, size, size)
    layers: list[_Tensor] = []
    rows: list[_Rows] = []
    for i, section in enumerate(sections[1:]):
        name = f"{section.kind}{i}"
        unknown = sorted(section.options.keys() - OPTIONS.get(section.kind, section.options.keys()))
        if unknown:
            raise ValueError(f"{cfg.name}: layer {i} [{section.kind}] has {', '.join(unknown)}, which the ONNX "
                             "converter does not support")
        if section.kind == "convolutional":
            x = _convolutional(graph, floats, section, x, name)
        elif section.kind == "shortcut":
            x = _shortcut(graph, section, x, layers[_index(section.get_int("from", -1), i)], name)
        elif section.kind == "route":
            x = _route(graph, [layers[_index(j, i)] for j in section.get_ints("layers")], name)
        elif section.kind == "maxpool":
            x = _maxpool(graph, section, x, name)
        elif section.kind == "upsample":
            x = _upsample(graph, section, x, name)
        elif section.kind == "yolo":
            rows.append(_yolo(graph, section, x, size, name))
        elif section.kind != "dropout":
            raise ValueError(f"{cfg.name}: layer {i} [{section.kind}] is not supported by the ONNX converter")
        layers.append(x)  # dropout and yolo pass their input on (nothing routes to a yolo layer)
    floats.check_used_up()
    if not rows:
        raise ValueError(f"{cfg.name}: no [yolo] layer")
    graph.op("Concat", [r.name for r in rows], "rows", axis=0)
    model = helper.make_model(
        helper.make_graph(
            graph.nodes,
            cfg.stem,
            [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, channels, size, size])],
            [helper.make_tensor_value_info("rows", TensorProto.FLOAT, [sum(r.count for r in rows), rows[0].columns])],
            initializer=graph.constants,
        ),
        opset_imports=[helper.make_opsetid("", OPSET)],
        producer_name="uav-tui darknet_onnx",
    )
    model.ir_version = IR_VERSION
    onnx.checker.check_model(model)
    return model


def _index(offset: int, layer: int) -> int:
    """Darknet's layer reference: negative counts back from ``layer``, else an absolute index."""
    return layer + offset if offset < 0 else offset


def _convolutional(graph: _Graph, floats: Weights, section: Section, x: _Tensor, name: str) -> _Tensor:
    filters, side, stride = section.get_int("filters", 1), section.get_int("size", 1), section.get_int("stride", 1)
    groups = section.get_int("groups", 1)
    pad = side // 2 if section.get_int("pad", 0) else section.get_int("padding", 0)
    # Darknet's order: biases, then (with batch norm) scales, means and variances, then the kernel
    bias = floats.take(filters)
    norm = [floats.take(filters) for _ in range(3)] if section.get_int("batch_normalize", 0) else None
    kernel = floats.take(filters * x.channels // groups * side * side).reshape(filters, -1, side, side)
    if norm is not None:
        scale, mean, variance = norm
        gain = scale / np.sqrt(variance + BN_EPSILON)
        kernel, bias = kernel * gain[:, None, None, None], bias - mean * gain
    out = graph.op(
        "Conv",
        [x.name, graph.const(kernel.astype(np.float32), f"{name}_kernel"), graph.const(bias, f"{name}_bias")],
        name,
        kernel_shape=[side, side],
        strides=[stride, stride],
        pads=[pad] * 4,
        group=groups,
    )
    activation = section.get("activation", "logistic")
    if activation == "leaky":
        out = graph.op("LeakyRelu", [out], f"{name}_leaky", alpha=LEAKY_SLOPE)
    elif activation != "linear":
        raise ValueError(f"[convolutional] activation={activation} is not supported by the ONNX converter")
    height, width = ((v + 2 * pad - side) // stride + 1 for v in (x.height, x.width))
    return _Tensor(out, filters, height, width)


def _shortcut(graph: _Graph, section: Section, x: _Tensor, other: _Tensor, name: str) -> _Tensor:
    if section.get("activation", "linear") != "linear":
        raise ValueError("[shortcut] other than a plain linear sum is not supported by the ONNX converter")
    return _Tensor(graph.op("Add", [x.name, other.name], name), x.channels, x.height, x.width)


def _route(graph: _Graph, sources: list[_Tensor], name: str) -> _Tensor:
    if len(sources) == 1:
        return sources[0]
    first = sources[0]
    out = graph.op("Concat", [s.name for s in sources], name, axis=1)
    return _Tensor(out, sum(s.channels for s in sources), first.height, first.width)


def _maxpool(graph: _Graph, section: Section, x: _Tensor, name: str) -> _Tensor:
    stride = section.get_int("stride", 1)
    side = section.get_int("size", stride)
    padding = section.get_int("padding", side - 1)  # Darknet's default; the odd pixel goes right and down
    before, after = padding // 2, padding - padding // 2
    out = graph.op("MaxPool", [x.name], name, kernel_shape=[side, side], strides=[stride, stride],
                   pads=[before, before, after, after])
    height, width = ((v + padding - side) // stride + 1 for v in (x.height, x.width))
    return _Tensor(out, x.channels, height, width)


def _upsample(graph: _Graph, section: Section, x: _Tensor, name: str) -> _Tensor:
    stride = section.get_int("stride", 2)
    scales = graph.const(np.array([1, 1, stride, stride], np.float32), f"{name}_scales")
    out = graph.op("Resize", [x.name, "", scales], name, mode="nearest",
                   coordinate_transformation_mode="asymmetric", nearest_mode="floor")
    return _Tensor(out, x.channels, x.height * stride, x.width * stride)


def _yolo(graph: _Graph, section: Section, x: _Tensor, size: int, name: str) -> _Rows:
    """The rows of one yolo layer, decoded as OpenCV's region layer does."""
    mask = section.get_ints("mask")
    classes = section.get_int("classes", 80)
    scale = section.get_float("scale_x_y", 1.0)
    if section.get_int("new_coords", 0):
        raise ValueError("[yolo] new_coords=1 (scaled YOLOv4) is not supported by the ONNX converter")
    anchors = np.array([float(v) for v in section.get("anchors", "").split(",")], np.float32).reshape(-1, 2)
    count, columns, h, w = len(mask), 5 + classes, x.height, x.width
    if x.channels != count * columns:
        raise ValueError(f"[yolo] expects {count} x {columns} input channels, the layer before has {x.channels}")
    # (1, anchors * columns, h, w) -> one row per cell row, cell column and anchor
    cells = graph.op("Reshape", [x.name, graph.const(np.array([1, count, columns, h, w], np.int64), f"{name}_5d")],
                     f"{name}_split_anchors")
    cells = graph.op("Transpose", [cells], f"{name}_cells_last", perm=[0, 3, 4, 1, 2])
    flat = graph.op("Reshape", [cells, graph.const(np.array([h * w * count, columns], np.int64), f"{name}_2d")],
                    f"{name}_raw")
    parts = graph.op("Split", [flat, graph.const(np.array([2, 2, 1, classes], np.int64), f"{name}_parts")],
                     f"{name}_part", outputs=4, axis=1)
    xy, wh, objectness, scores = (f"{parts}_{i}" for i in range(4))
    # centre: ((sigmoid - 0.5) * scale + 0.5 + cell) / cells, as a fraction of the input
    row, column, _ = np.meshgrid(np.arange(h), np.arange(w), np.arange(count), indexing="ij")
    offset = np.stack([column, row], axis=-1).reshape(-1, 2) + 0.5 * (1 - scale)
    xy = graph.op("Mul", [graph.op("Sigmoid", [xy], f"{name}_xy_sigmoid"),
                          graph.const(np.array(scale, np.float32), f"{name}_xy_scale")], f"{name}_xy_scaled")
    xy = graph.op("Add", [xy, graph.const(offset.astype(np.float32), f"{name}_cell")], f"{name}_xy_cells")
    xy = graph.op("Div", [xy, graph.const(np.array([w, h], np.float32), f"{name}_grid")], f"{name}_xy")
    # size: exp * anchor, as a fraction of the input
    anchor = np.tile(anchors[mask] / size, (h * w, 1)).astype(np.float32)
    wh = graph.op("Mul", [graph.op("Exp", [wh], f"{name}_wh_exp"), graph.const(anchor, f"{name}_anchor")],
                  f"{name}_wh")
    objectness = graph.op("Sigmoid", [objectness], f"{name}_objectness")
    scores = graph.op("Mul", [graph.op("Sigmoid", [scores], f"{name}_class_sigmoid"), objectness],
                      f"{name}_class_scores")
    floor = graph.const(np.array(SCORE_FLOOR, np.float32), f"{name}_floor")
    kept = graph.op("Greater", [scores, floor], f"{name}_above_floor")
    scores = graph.op("Where", [kept, scores, graph.const(np.array(0, np.float32), f"{name}_zero")],
                      f"{name}_scores")
    return _Rows(graph.op("Concat", [xy, wh, objectness, scores], name, axis=1), h * w * count, columns)
