"""VTK XML files (`.vti` image data, `.vtp` polydata) read with the standard library and numpy.

Reads what the co-simulation writes (arrays appended raw, zlib-compressed, UInt64 headers) and
the other encodings of VTK's XML format: appended base64, inline base64 (`format="binary"`)
and ASCII, compressed with zlib or not, with UInt32 or UInt64 headers, little or big endian.
"""

import base64
import re
import xml.etree.ElementTree as ET
import zlib

import numpy as np

_TYPES = {
    "Int8": "i1", "UInt8": "u1", "Int16": "i2", "UInt16": "u2", "Int32": "i4", "UInt32": "u4",
    "Int64": "i8", "UInt64": "u8", "Float32": "f4", "Float64": "f8",
}


class VtkFile:
    """A decoded file: `kind` ("ImageData" or "PolyData"), `dataset` and `piece` (the XML
    attributes of those elements), and `arrays`, a dict from (section, name) to a numpy array
    of shape (tuples,) or (tuples, components); section is "CellData", "PointData", "Points",
    "Verts", "Lines", "Polys" or "Strips"."""

    def __init__(self, kind, dataset, piece, arrays):
        self.kind = kind
        self.dataset = dataset
        self.piece = piece
        self.arrays = arrays

    def array(self, section, name):
        """The array `name` of `section` (KeyError when absent)."""
        return self.arrays[(section, name)]

    def names(self, section):
        """The names of the arrays of `section`, in file order."""
        return [n for (s, n) in self.arrays if s == section]


def _blocks(raw, header_dtype, compressed):
    """Decodes one array's bytes (header included) from `raw`; returns (payload, bytes used)."""
    hs = np.dtype(header_dtype).itemsize
    if not compressed:
        (n,) = np.frombuffer(raw[:hs], dtype=header_dtype)
        return bytes(raw[hs:hs + int(n)]), hs + int(n)
    nblocks = int(np.frombuffer(raw[:hs], dtype=header_dtype)[0])
    header = np.frombuffer(raw[:(3 + nblocks) * hs], dtype=header_dtype).astype(np.int64)
    at = (3 + nblocks) * hs
    out = []
    for size in header[3:]:
        out.append(zlib.decompress(raw[at:at + int(size)]))
        at += int(size)
    return b"".join(out), at


def _b64_blocks(text, header_dtype, compressed):
    """As `_blocks` for base64 text (VTK encodes a compressed array's header apart from its
    blocks)."""
    text = re.sub(rb"\s+", b"", text)
    if not compressed:
        return _blocks(base64.b64decode(text), header_dtype, False)[0]
    hs = np.dtype(header_dtype).itemsize
    first = base64.b64decode(text[:4 * -(-hs // 3)])
    nblocks = int(np.frombuffer(first[:hs], dtype=header_dtype)[0])
    hlen = 4 * -(-((3 + nblocks) * hs) // 3)
    header = base64.b64decode(text[:hlen])
    blocks = base64.b64decode(text[hlen:])
    sizes = np.frombuffer(header[:(3 + nblocks) * hs], dtype=header_dtype)[3:].astype(np.int64)
    out, at = [], 0
    for size in sizes:
        out.append(zlib.decompress(blocks[at:at + int(size)]))
        at += int(size)
    return b"".join(out)


def parse(data):
    """Decodes the bytes of a `.vti` or `.vtp` file into a `VtkFile`."""
    marker = data.find(b"<AppendedData")
    appended = None
    if marker >= 0:
        tag_end = data.index(b">", marker)
        encoding = re.search(rb'encoding="(\w+)"', data[marker:tag_end])
        encoding = encoding.group(1).decode() if encoding else "raw"
        start = data.index(b"_", tag_end) + 1
        if encoding == "raw":
            appended = ("raw", data[start:])
        else:
            end = data.index(b"</AppendedData>", start)
            appended = ("base64", data[start:end].strip())
        head = data[:marker] + b"</VTKFile>"
        # The unclosed elements before <AppendedData> close at </VTKFile>.
        root = ET.fromstring(_close(head.decode("utf-8")))
    else:
        root = ET.fromstring(data)
    if root.tag != "VTKFile":
        raise ValueError("not a VTK XML file")
    order = "<" if root.get("byte_order", "LittleEndian") == "LittleEndian" else ">"
    header_dtype = order + ("u8" if root.get("header_type", "UInt32") == "UInt64" else "u4")
    compressed = root.get("compressor") is not None
    kind = root.get("type")
    dataset = root.find(kind)
    piece = dataset.find("Piece")
    arrays = {}
    for section in piece:
        for el in section.iter("DataArray"):
            dtype = np.dtype(order + _TYPES[el.get("type")])
            fmt = el.get("format", "ascii")
            if fmt == "ascii":
                values = np.array((el.text or "").split(), dtype=dtype)
            elif fmt == "binary":
                payload = _b64_blocks((el.text or "").encode(), header_dtype, compressed)
                values = np.frombuffer(payload, dtype=dtype)
            else:
                offset = int(el.get("offset"))
                enc, blob = appended
                if enc == "raw":
                    payload = _blocks(blob[offset:], header_dtype, compressed)[0]
                else:
                    payload = _b64_blocks(blob[offset:], header_dtype, compressed)
                values = np.frombuffer(payload, dtype=dtype)
            components = int(el.get("NumberOfComponents", "1"))
            if components > 1:
                values = values.reshape(-1, components)
            arrays[(section.tag, el.get("Name"))] = values
    return VtkFile(kind, dict(dataset.attrib), dict(piece.attrib), arrays)


def _close(head):
    """`head` (XML cut before <AppendedData>, ending with </VTKFile>) with the elements still
    open before </VTKFile> closed."""
    body = head[: head.rindex("</VTKFile>")]
    stack = []
    for m in re.finditer(r"<(/?)([A-Za-z]\w*)[^>]*?(/?)>", body):
        closing, name, empty = m.group(1), m.group(2), m.group(3)
        if closing:
            while stack and stack.pop() != name:
                pass
        elif not empty:
            stack.append(name)
    tail = "".join(f"</{name}>" for name in reversed(stack))
    return body + tail


def read(path):
    """Reads the file at `path`."""
    with open(path, "rb") as f:
        return parse(f.read())
