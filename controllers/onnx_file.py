"""What an ONNX file holds, read before onnxruntime sees it and without the onnx package.

`controllers.onnx_policy` hands onnxruntime the very bytes whose SHA-256 the contract records, so
the hash covers the whole graph, except what the graph asks the runtime to read from elsewhere:
tensors stored as external data (a file beside the model, resolved by onnxruntime relative to
the model's folder or the current folder). `scan_model` walks the model's protocol-buffer
encoding (docs: onnx/onnx.proto; field numbers below) and refuses

* external data anywhere (an initializer, a Constant's tensor, a sparse tensor, a function's or
  a subgraph's),
* a stored tensor of more than `MAX_TENSOR_ELEMENTS` elements by its declared dimensions (a
  2^40-element initializer is refused here, before anything allocates it), a negative dimension,
* messages nested deeper than `MAX_DEPTH` and anything that is not well-formed protocol-buffer
  encoding,

each as a one-line ValueError naming the file. It returns the model's metadata properties, which
the runtime compares with the contract. The walk reads only the fields it needs and copies
nothing but the metadata strings, so its cost is one pass over the bytes.
"""

from __future__ import annotations

from typing import Any

__all__ = ["MAX_DEPTH", "MAX_TENSOR_ELEMENTS", "scan_model"]

MAX_TENSOR_ELEMENTS = 2**26  # a stored tensor's elements: 256 MiB of float32
MAX_DEPTH = 64  # nested messages (the exports nest 4: model, graph, node, attribute, tensor)

# Wire types of the protocol-buffer encoding.
_VARINT, _FIXED64, _BYTES, _FIXED32 = 0, 1, 2, 5
# The messages that can hold a tensor, and which of their fields are such messages (onnx.proto).
_CHILDREN: dict[str, dict[int, str]] = {
    # ModelProto: 7 graph, 20 training_info, 25 functions
    "model": {7: "graph", 20: "training", 25: "function"},
    # GraphProto: 1 node, 5 initializer, 15 sparse_initializer
    "graph": {1: "node", 5: "tensor", 15: "sparse"},
    # NodeProto: 5 attribute
    "node": {5: "attribute"},
    # AttributeProto: 5 t, 6 g, 10 tensors, 11 graphs, 22 sparse_tensor, 23 sparse_tensors
    "attribute": {5: "tensor", 6: "graph", 10: "tensor", 11: "graph", 22: "sparse", 23: "sparse"},
    # FunctionProto: 7 node, 11 attribute_proto
    "function": {7: "node", 11: "attribute"},
    # TrainingInfoProto: 1 initialization, 2 algorithm
    "training": {1: "graph", 2: "graph"},
    # SparseTensorProto: 1 values, 2 indices
    "sparse": {1: "tensor", 2: "tensor"},
    "tensor": {},
}
_MODEL_METADATA = 14  # ModelProto.metadata_props (StringStringEntryProto: 1 key, 2 value)
_DIMS = {"tensor": 1, "sparse": 3}  # TensorProto.dims, SparseTensorProto.dims (int64)
_EXTERNAL_DATA = 13  # TensorProto.external_data
_DATA_LOCATION = 14  # TensorProto.data_location: 1 = EXTERNAL


class _Malformed(Exception):
    pass


def _varint(buf: memoryview, pos: int, end: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        if pos >= end or shift > 63:
            raise _Malformed
        byte = buf[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value, pos
        shift += 7


def _fields(buf: memoryview, start: int, end: int):
    """(field number, wire type, value) of one message's fields; the value of a varint is the
    integer, of a length-delimited field its (start, end)."""
    pos = start
    while pos < end:
        key, pos = _varint(buf, pos, end)
        field, wire = key >> 3, key & 7
        if field == 0:
            raise _Malformed
        if wire == _VARINT:
            value, pos = _varint(buf, pos, end)
            yield field, wire, value
        elif wire == _BYTES:
            length, pos = _varint(buf, pos, end)
            if pos + length > end:
                raise _Malformed
            yield field, wire, (pos, pos + length)
            pos += length
        elif wire in (_FIXED64, _FIXED32):
            pos += 8 if wire == _FIXED64 else 4
            if pos > end:
                raise _Malformed
        else:  # groups (wire types 3, 4) are not used by ONNX
            raise _Malformed


def _dims(buf: memoryview, wire: int, value: Any) -> list[int]:
    """The int64 dimensions of one dims field: a single varint, or a packed run of them."""
    if wire == _VARINT:
        raw = [value]
    elif wire == _BYTES:
        raw, pos = [], value[0]
        while pos < value[1]:
            item, pos = _varint(buf, pos, value[1])
            raw.append(item)
    else:
        raise _Malformed
    return [v - (1 << 64) if v >= 1 << 63 else v for v in raw]


def _text(buf: memoryview, span: tuple[int, int]) -> str:
    return bytes(buf[span[0] : span[1]]).decode("utf-8", errors="replace")


def scan_model(data: bytes, where: Any) -> dict[str, str]:
    """The metadata properties of the serialised ONNX model ``data`` after checking it holds no
    external data, no oversized tensor and no malformed or too deeply nested message (module
    doc); a one-line ValueError naming ``where`` otherwise."""
    buf = memoryview(data)
    metadata: dict[str, str] = {}
    stack: list[tuple[str, int, int, int]] = [("model", 0, len(buf), 0)]
    try:
        while stack:
            kind, start, end, depth = stack.pop()
            if depth > MAX_DEPTH:
                raise ValueError(
                    f"ONNX graph {where}: messages nested deeper than {MAX_DEPTH}; refused"
                )
            elements = 1
            for field, wire, value in _fields(buf, start, end):
                child = _CHILDREN[kind].get(field)
                if child is not None and wire == _BYTES:
                    stack.append((child, *value, depth + 1))
                elif kind == "model" and field == _MODEL_METADATA and wire == _BYTES:
                    entry = dict.fromkeys((1, 2), "")
                    for key, entry_wire, span in _fields(buf, *value):
                        if key in entry and entry_wire == _BYTES:
                            entry[key] = _text(buf, span)
                    metadata[entry[1]] = entry[2]
                elif field == _DIMS.get(kind):
                    for dim in _dims(buf, wire, value):
                        if dim < 0:
                            raise ValueError(
                                f"ONNX graph {where}: a stored tensor has dimension {dim} < 0"
                            )
                        elements *= dim
                        if elements > MAX_TENSOR_ELEMENTS:
                            raise ValueError(
                                f"ONNX graph {where}: a stored tensor of {elements:,} or more "
                                f"elements exceeds {MAX_TENSOR_ELEMENTS:,}; refused before "
                                "allocating it"
                            )
                elif kind == "tensor" and (
                    field == _EXTERNAL_DATA or (field == _DATA_LOCATION and value == 1)
                ):
                    raise ValueError(
                        f"ONNX graph {where} keeps tensors as external data (files beside it, "
                        "which its contract's SHA-256 does not cover); auv-gym runs only "
                        "self-contained graphs: re-export it"
                    )
    except _Malformed:
        raise ValueError(f"ONNX graph {where} is not a well-formed ONNX model") from None
    return metadata
