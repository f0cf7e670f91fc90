#!/usr/bin/env python3
"""Writes the seed inputs of the fuzz targets into fuzz/corpus/<target>/seed_*: small valid files
of every format and variant the readers take (byte orders, compressions, encodings, polygon
kinds). Standard library only; the .vdb seeds are written by the program itself.

  fuzz/make_seeds.py PATH/TO/voxsculpt
"""
import gzip
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")

# A 4 x 4 x 4 volume: a 2 x 2 x 2 block of label 1 and one voxel of label 2.
DIMS = (4, 4, 4)
VOXELS = [0] * 64
for k in (1, 2):
    for j in (1, 2):
        for i in (1, 2):
            VOXELS[i + 4 * (j + 4 * k)] = 1
VOXELS[3 + 4 * (3 + 4 * 3)] = 2


def seed(target, name, data):
    os.makedirs(os.path.join(CORPUS, target), exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(os.path.join(CORPUS, target, "seed_" + name), mode) as f:
        f.write(data)


def nifti1(datatype, bitpix, fmt, endian="<", slope=0.0, sform=True):
    h = bytearray(348)
    struct.pack_into(endian + "i", h, 0, 348)
    struct.pack_into(endian + "8h", h, 40, 3, *DIMS, 1, 1, 1, 1)
    struct.pack_into(endian + "hh", h, 70, datatype, bitpix)
    struct.pack_into(endian + "8f", h, 76, 1.0, 0.5, 0.5, 1.5, 1, 1, 1, 1)
    struct.pack_into(endian + "fff", h, 108, 352.0, slope, -1024.0 if slope else 0.0)
    struct.pack_into(endian + "hh", h, 252, 0, 1 if sform else 0)
    if sform:
        struct.pack_into(endian + "12f", h, 280, 0.5, 0, 0, -10, 0, 0.5, 0, 20, 0, 0, 1.5, 5)
    h[344:348] = b"n+1\0"
    data = b"".join(struct.pack(endian + fmt, v) for v in VOXELS)
    return bytes(h) + b"\0\0\0\0" + data


def nifti2():
    h = bytearray(540)
    struct.pack_into("<i", h, 0, 540)
    h[4:12] = b"n+2\0\r\n\x1a\n"
    struct.pack_into("<hh", h, 12, 2, 8)  # uint8
    struct.pack_into("<8q", h, 16, 3, *DIMS, 1, 1, 1, 1)
    struct.pack_into("<8d", h, 104, 1, 1, 1, 1, 1, 1, 1, 1)
    struct.pack_into("<q", h, 168, 544)
    return bytes(h) + b"\0\0\0\0" + bytes(VOXELS)


def metaimage(compressed):
    data = bytes(VOXELS)
    if compressed:
        data = zlib.compress(data)
    head = ("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
            f"CompressedData = {'True' if compressed else 'False'}\n"
            + (f"CompressedDataSize = {len(data)}\n" if compressed else "")
            + "TransformMatrix = 1 0 0 0 1 0 0 0 1\nOffset = -5 0 2.5\nElementSpacing = 0.5 0.5 1.25\n"
            "DimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n")
    return head.encode() + data


def nrrd(encoding):
    head = ("NRRD0004\ntype: unsigned char\ndimension: 3\nspace: left-posterior-superior\nsizes: 4 4 4\n"
            "space directions: (0.5,0,0) (0,0.5,0) (0,0,1.5)\nspace origin: (1,2,3)\n"
            f"encoding: {encoding}\n\n")
    if encoding == "raw":
        data = bytes(VOXELS)
    elif encoding == "gzip":
        data = gzip.compress(bytes(VOXELS))
    else:
        data = " ".join(str(v) for v in VOXELS).encode() + b"\n"
    return head.encode() + data


def nrrd_short_big_endian():
    head = ("NRRD0005\ntype: short\ndimension: 3\nsizes: 4 4 4\nspacings: 1 1 2\nendian: big\nencoding: raw\n\n")
    return head.encode() + b"".join(struct.pack(">h", v * 300 - 1000) for v in VOXELS)


def inr(kind):
    types = {"u8": ("unsigned fixed", 8, "B"), "i16": ("signed fixed", 16, "h"), "f32": ("float", 32, "f")}
    name, bits, fmt = types[kind]
    h = (f"#INRIMAGE-4#{{\nXDIM=4\nYDIM=4\nZDIM=4\nVDIM=1\nTYPE={name}\nPIXSIZE={bits} bits\nSCALE=2**0\n"
         "CPU=decm\nVX=0.5\nVY=0.5\nVZ=1.5\nXO=1\nYO=2\nZO=3\n")
    h = h + "\n" * (256 - 4 - len(h)) + "##}\n"
    return h.encode() + b"".join(struct.pack("<" + fmt, v) for v in VOXELS)


CUBE_V = [(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0), (0, 0, 10), (10, 0, 10), (10, 10, 10), (0, 10, 10)]
CUBE_QUADS = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
TET_V = [(0, 0, 0), (10, 0, 0), (0, 10, 0), (0, 0, 10)]
TET_F = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def dicom(implicit=False, big_endian=False):
    """One 4 x 4 CT slice of int16 with a rescale: preamble, "DICM", the file meta group (always
    explicit VR little endian), then the data set in the transfer syntax named."""
    syntax = "1.2.840.10008.1.2" if implicit else "1.2.840.10008.1.2.2" if big_endian else "1.2.840.10008.1.2.1"

    def element(group, number, vr, value, implicit_vr, endian):
        if isinstance(value, str):
            value = value.encode("ascii")
            value += b"\0" if vr == "UI" and len(value) % 2 else b" " if len(value) % 2 else b""
        head = struct.pack(endian + "HH", group, number)
        if implicit_vr:
            return head + struct.pack(endian + "I", len(value)) + value
        if vr in ("OB", "OW", "UN", "SQ", "UT"):
            return head + vr.encode() + b"\0\0" + struct.pack(endian + "I", len(value)) + value
        return head + vr.encode() + struct.pack(endian + "H", len(value)) + value

    endian = ">" if big_endian else "<"
    meta = b"".join(element(2, n, vr, v, False, "<") for n, vr, v in [
        (1, "OB", b"\0\1"), (2, "UI", "1.2.840.10008.5.1.4.1.1.2"), (3, "UI", "1.2.3.4.5.6.7"), (0x10, "UI", syntax)])
    meta = element(2, 0, "UL", struct.pack("<I", len(meta)), False, "<") + meta
    pixels = struct.pack(endian + "16h", *[v * 10 - 1000 for v in range(16)])
    data = b"".join(element(g, n, vr, v, implicit, endian) for g, n, vr, v in [
        (0x0008, 0x0016, "UI", "1.2.840.10008.5.1.4.1.1.2"), (0x0008, 0x0018, "UI", "1.2.3.4.5.6.7"),
        (0x0008, 0x0060, "CS", "CT"), (0x0008, 0x103E, "LO", "seed"), (0x0018, 0x0050, "DS", "1.5"),
        (0x0020, 0x000E, "UI", "1.2.3.4.5.6.8"), (0x0020, 0x0011, "IS", "1"),
        (0x0020, 0x0032, "DS", "-10\\20.5\\3"), (0x0020, 0x0037, "DS", "1\\0\\0\\0\\1\\0"),
        (0x0028, 0x0002, "US", struct.pack(endian + "H", 1)), (0x0028, 0x0004, "CS", "MONOCHROME2"),
        (0x0028, 0x0010, "US", struct.pack(endian + "H", 4)), (0x0028, 0x0011, "US", struct.pack(endian + "H", 4)),
        (0x0028, 0x0030, "DS", "0.5\\0.75"), (0x0028, 0x0100, "US", struct.pack(endian + "H", 16)),
        (0x0028, 0x0101, "US", struct.pack(endian + "H", 16)), (0x0028, 0x0102, "US", struct.pack(endian + "H", 15)),
        (0x0028, 0x0103, "US", struct.pack(endian + "H", 1)), (0x0028, 0x1052, "DS", "-1024"),
        (0x0028, 0x1053, "DS", "1"), (0x7FE0, 0x0010, "OW", pixels)])
    return b"\0" * 128 + b"DICM" + meta + data


def segmentation(layers=2, extra=""):
    """A 3D Slicer segmentation of the 4 x 4 x 4 volume: "block" (label 1) and "spot" (label 2) in
    layer 0, and with two layers an overlapping "core" in layer 1."""
    pairs = ["Segmentation_MasterRepresentation:=Binary labelmap",
             "Segmentation_ContainedRepresentationNames:=Binary labelmap|",
             "Segmentation_ReferenceImageExtentOffset:=0 0 0"]
    segments = [("block", 1, 0, "0.9 0.5 0.4"), ("spot", 2, 0, "0.2 0.6 0.8")] + ([("core", 1, 1, "0.5 0.9 0.5")] if layers == 2 else [])
    for n, (name, value, layer, color) in enumerate(segments):
        pairs += [f"Segment{n}_ID:=Segment_{n + 1}", f"Segment{n}_Name:={name}", f"Segment{n}_Color:={color}",
                  f"Segment{n}_LabelValue:={value}", f"Segment{n}_Layer:={layer}", f"Segment{n}_Extent:=0 3 0 3 0 3",
                  f"Segment{n}_Tags:=|"]
    data = bytearray()
    for v in VOXELS:
        data.append(v)
        if layers == 2:
            data.append(1 if v == 1 else 0)
    sizes = f"{layers} 4 4 4" if layers == 2 else "4 4 4"
    directions = ("none " if layers == 2 else "") + "(1.5,0,0) (0,1.5,0) (0,0,2)"
    kinds = ("list " if layers == 2 else "") + "domain domain domain"
    head = (f"NRRD0004\ntype: uint8\ndimension: {3 + (layers == 2)}\nspace: left-posterior-superior\nsizes: {sizes}\n"
            f"space directions: {directions}\nkinds: {kinds}\nencoding: gzip\nspace origin: (10,-20,5)\n"
            + "\n".join(pairs) + "\n" + extra + "\n")
    return head.encode("ascii") + gzip.compress(bytes(data))


def triangles(faces):
    return [(f[0], f[i], f[i + 1]) for f in faces for i in range(1, len(f) - 1)]


def obj_files():
    seed("obj", "tetrahedron.obj", "".join(f"v {x} {y} {z}\n" for x, y, z in TET_V)
         + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in TET_F))
    text = "# a cube of quads, corners with texture and normal indices\no cube\n"
    text += "".join(f"v {x} {y} {z}\n" for x, y, z in CUBE_V) + "vt 0 0\nvn 0 0 1\ng sides\nusemtl clay\n"
    text += "".join("f " + " ".join(f"{i + 1}/1/1" for i in q) + "\n" for q in CUBE_QUADS[:3])
    text += "".join("f " + " ".join(f"-{8 - i}//1" for i in q) + "\n" for q in CUBE_QUADS[3:])
    seed("obj", "cube_quads.obj", text)


def ply_files():
    head = lambda fmt: (f"ply\nformat {fmt} 1.0\ncomment cube\nelement vertex 8\nproperty float x\nproperty float y\n"
                        "property float z\nproperty uchar red\nelement face 6\nproperty list uchar int vertex_indices\n"
                        "end_header\n")
    seed("ply", "cube_ascii.ply", head("ascii") + "".join(f"{x} {y} {z} 200\n" for x, y, z in CUBE_V)
         + "".join("4 " + " ".join(map(str, q)) + "\n" for q in CUBE_QUADS))
    for name, e in (("little_endian", "<"), ("big_endian", ">")):
        body = b"".join(struct.pack(e + "fffB", x, y, z, 200) for x, y, z in CUBE_V)
        body += b"".join(struct.pack(e + "B4i", 4, *q) for q in CUBE_QUADS)
        seed("ply", f"cube_{name}.ply", head(f"binary_{name}").encode() + body)


def stl_files():
    tris = triangles(TET_F)
    text = "solid tet\n"
    for a, b, c in tris:
        text += "facet normal 0 0 0\nouter loop\n" + "".join(
            "vertex {} {} {}\n".format(*TET_V[i]) for i in (a, b, c)) + "endloop\nendfacet\n"
    seed("stl", "tetrahedron_ascii.stl", text + "endsolid tet\n")
    body = b"binary tetrahedron".ljust(80, b" ") + struct.pack("<I", len(tris))
    for a, b, c in tris:
        body += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *TET_V[i]) for i in (a, b, c)) + b"\0\0"
    seed("stl", "tetrahedron_binary.stl", body)


def off_files():
    seed("off", "tetrahedron.off", "OFF\n# a tetrahedron\n4 4 6\n" + "".join(f"{x} {y} {z}\n" for x, y, z in TET_V)
         + "".join(f"3 {a} {b} {c}\n" for a, b, c in TET_F))
    seed("off", "cube_colours.off", "COFF\n8 6 12\n" + "".join(f"{x} {y} {z} 255 0 0 255\n" for x, y, z in CUBE_V)
         + "".join("4 " + " ".join(map(str, q)) + "\n" for q in CUBE_QUADS))


def scene_files():
    for name in ("beam.json", "clay.json", "press_and_cut_two_phase.json", "wet_push.json", "bar_cut_isxfem.json",
                 "push_broad_vs_sharp.json", "utube_cut.json"):
        shutil.copy(os.path.join(ROOT, "data", "scenes", name), os.path.join(CORPUS, "scene", "seed_" + name))


def recording_files():
    rows = ["t_s,x_mm,y_mm,z_mm,qw,qx,qy,qz,buttons,fx_n,fy_n,fz_n"]
    for i in range(12):
        rows.append(f"{i * 0.001:.17g},120,10,{150 - i * 0.05:.17g},1,0,0,0,{1 if i > 5 else 0},0,0,{-0.01 * i:.17g}")
    seed("recording", "press.csv", "\n".join(rows) + "\n")
    rows = [rows[0], "0,0,0,0,0.70710678118654757,0,0.70710678118654757,0,0,0,0,0",
            "0.5,1e-3,-2,3.5,0.70710678118654757,0,0.70710678118654757,0,3,0.25,-0.5,1"]
    seed("recording", "rotated.csv", "\n".join(rows) + "\n")


def ccd_files():
    for kind in ("vertex-face", "edge-edge"):
        with open(os.path.join(ROOT, "data", "ccd-queries", "unit-tests", kind, "data_0_0.csv")) as f:
            lines = f.read().splitlines()
        seed("ccd_queries", f"{kind}_first.csv", "\n".join(lines[:16]) + "\n")


def vdb_files(voxsculpt):
    os.makedirs(os.path.join(CORPUS, "vdb"), exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        volume = os.path.join(tmp, "labels.nrrd")
        with open(volume, "wb") as f:
            f.write(nrrd("raw"))
        subprocess.run([voxsculpt, "-q", "import", volume, "-o", os.path.join(CORPUS, "vdb", "seed_labels.vdb")],
                       check=True)
        subprocess.run([voxsculpt, "-q", "phantom", "block", "--size-mm", "4", "3", "2", "-o",
                        os.path.join(CORPUS, "vdb", "seed_block.vdb")], check=True)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    seed("nifti", "u8_sform.nii", nifti1(2, 8, "B"))
    seed("nifti", "i16_scaled_big_endian.nii", nifti1(4, 16, "h", ">", slope=2.0, sform=False))
    seed("nifti", "f32.nii.gz", gzip.compress(nifti1(16, 32, "f")))
    seed("nifti", "nifti2_u8.nii", nifti2())
    seed("metaimage", "raw.mha", metaimage(False))
    seed("metaimage", "zlib.mha", metaimage(True))
    for encoding in ("raw", "gzip", "ascii"):
        seed("nrrd", f"{encoding}.nrrd", nrrd(encoding))
    seed("nrrd", "short_big_endian.nrrd", nrrd_short_big_endian())
    for kind in ("u8", "i16", "f32"):
        seed("inr", f"{kind}.inr", inr(kind))
    seed("inr", "u8.inr.gz", gzip.compress(inr("u8")))
    seed("segmentation", "two_layers.seg.nrrd", segmentation(2))
    seed("segmentation", "one_layer.seg.nrrd", segmentation(1))
    seed("dicom", "ct_explicit.dcm", dicom())
    seed("dicom", "ct_implicit.dcm", dicom(implicit=True))
    seed("dicom", "ct_big_endian.dcm", dicom(big_endian=True))
    obj_files()
    ply_files()
    stl_files()
    off_files()
    os.makedirs(os.path.join(CORPUS, "scene"), exist_ok=True)
    scene_files()
    recording_files()
    ccd_files()
    vdb_files(sys.argv[1])


if __name__ == "__main__":
    main()
