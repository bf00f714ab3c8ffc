"""The glTF writer shared by the bench scripts that write big models (big_mesh.py,
big_emissive.py): one binary buffer, its views and accessors."""
import struct


class Buffer:
    def __init__(self):
        self.bin = bytearray()
        self.views = []
        self.accessors = []

    def add(self, data, fmt, count, ty, comp, minmax=None):
        """Appends `data` (struct format `fmt`, 4-byte aligned) as a view and an accessor of
        `count` elements of type `ty` and component type `comp`; returns the accessor."""
        while len(self.bin) % 4:
            self.bin.append(0)
        self.views.append({"buffer": 0, "byteOffset": len(self.bin),
                           "byteLength": struct.calcsize(fmt) * len(data)})
        self.bin.extend(struct.pack(f"<{len(data)}{fmt}", *data))
        acc = {"bufferView": len(self.views) - 1, "count": count, "type": ty,
               "componentType": comp}
        if minmax:
            acc["min"], acc["max"] = minmax
        self.accessors.append(acc)
        return len(self.accessors) - 1


def bounds(p):
    """The min and max corners of flat xyz positions `p`."""
    xs, ys, zs = p[0::3], p[1::3], p[2::3]
    return [min(xs), min(ys), min(zs)], [max(xs), max(ys), max(zs)]
