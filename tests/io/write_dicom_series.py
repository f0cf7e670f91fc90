#!/usr/bin/python3
"""Writes an INRIMAGE-4 volume (.inr or .inr.gz) as a DICOM series with pydicom, an implementation
independent of the reader under test (GDCM), for the DICOM tests.

One file per slice, CT modality, 16-bit signed stored values: the INR's values themselves (a label
map), or with --rescale stored as 2 v + 1000 with slope 0.5 and intercept -500, so that only the
rescale gives the INR's value back (as Hounsfield units come from a CT's stored values). Options make the series awkward the way real exports are:
file names shuffled, instance numbers reversed, an oblique orientation, and the defects the reader
must refuse (a missing slice, two slices at one position, gantry tilt), and the rounding a scanner
applies to the positions it writes (--round-mm, which the reader must accept).

Usage: write_dicom_series.py IN.inr[.gz] OUT_DIR [--shuffle] [--rotate-deg A] [--tilt-deg T]
         [--drop-slice K] [--duplicate-slice K] [--slices N] [--rle] [--rescale] [--series-number S]
         [--description TEXT] [--round-mm R]
"""
import argparse
import gzip
import math
import os
import random

import numpy as np
import pydicom
from pydicom.dataset import FileDataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian, RLELossless, generate_uid

INR_TYPES = {("unsigned fixed", 8): np.uint8, ("unsigned fixed", 16): np.uint16,
             ("signed fixed", 16): np.int16, ("float", 32): np.float32}


def read_inr(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rb") as f:
        raw = f.read()
    end = raw.index(b"##}\n") + 4
    fields = dict(line.split("=", 1) for line in raw[:end].decode("ascii").splitlines() if "=" in line)
    dims = [int(fields[k]) for k in ("XDIM", "YDIM", "ZDIM")]
    bits = int(fields["PIXSIZE"].split()[0])
    dtype = np.dtype(INR_TYPES[(fields["TYPE"], bits)])
    dtype = dtype.newbyteorder(">" if fields.get("CPU", "decm") in ("sun", "sgi") else "<")
    spacing = [float(fields.get(k, "1")) for k in ("VX", "VY", "VZ")]
    origin = [float(fields.get(k, "0")) for k in ("XO", "YO", "ZO")]
    voxels = np.frombuffer(raw[end:end + dims[0] * dims[1] * dims[2] * dtype.itemsize], dtype=dtype)
    return voxels.reshape(dims[2], dims[1], dims[0]), spacing, origin


def rotation(degrees):
    """A rotation by `degrees` about the axis (1, 2, 3): no index axis stays aligned with the world."""
    axis = np.array([1.0, 2.0, 3.0]) / math.sqrt(14.0)
    a = math.radians(degrees)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k


def ds_text(values):
    return [f"{v:.10g}" for v in values]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("inr")
    p.add_argument("out")
    p.add_argument("--shuffle", action="store_true", help="file names out of order, instance numbers reversed")
    p.add_argument("--rotate-deg", type=float, default=0.0)
    p.add_argument("--tilt-deg", type=float, default=0.0)
    p.add_argument("--drop-slice", type=int, default=-1)
    p.add_argument("--duplicate-slice", type=int, default=-1)
    p.add_argument("--slices", type=int, default=0, help="write only the first N slices")
    p.add_argument("--rle", action="store_true", help="RLE Lossless transfer syntax")
    p.add_argument("--rescale", action="store_true", help="stored 2 v + 1000, slope 0.5, intercept -500")
    p.add_argument("--series-number", type=int, default=3)
    p.add_argument("--description", default="liver labels")
    p.add_argument("--round-mm", type=float, default=0.0,
                   help="write ImagePositionPatient rounded to multiples of R mm, as scanners do")
    a = p.parse_args()

    voxels, spacing, origin = read_inr(a.inr)
    if a.slices:
        voxels = voxels[:a.slices]
    os.makedirs(a.out, exist_ok=True)
    r = rotation(a.rotate_deg)
    row_dir, col_dir, normal = r[:, 0], r[:, 1], r[:, 2]
    # The tilt shears the stack along the column direction, as a tilted gantry does.
    shear = math.tan(math.radians(a.tilt_deg))
    stored = (voxels.astype(np.int32) * (2 if a.rescale else 1) + (1000 if a.rescale else 0)).astype(np.int16)
    study, series, frame = generate_uid(), generate_uid(), generate_uid()
    slices = [k for k in range(voxels.shape[0]) if k != a.drop_slice]
    if a.duplicate_slice >= 0:
        slices.append(a.duplicate_slice)
    names = list(range(len(slices)))
    if a.shuffle:
        random.Random(7).shuffle(names)
    for n, k in enumerate(slices):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = pydicom.uid.CTImageStorage
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds = FileDataset(None, {}, file_meta=meta, preamble=b"\0" * 128)
        ds.is_little_endian, ds.is_implicit_VR = True, False
        ds.SOPClassUID, ds.SOPInstanceUID = meta.MediaStorageSOPClassUID, meta.MediaStorageSOPInstanceUID
        ds.Modality = "CT"
        ds.PatientName, ds.PatientID = "Test^Liver", "VOX-TEST-0001"
        ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
        ds.SeriesNumber = a.series_number
        ds.SeriesDescription = a.description
        ds.InstanceNumber = len(slices) - n if a.shuffle else n + 1
        position = np.array(origin) + k * spacing[2] * (normal + shear * col_dir)
        if a.round_mm > 0:
            position = np.round(position / a.round_mm) * a.round_mm
        ds.ImagePositionPatient = ds_text(position)
        ds.ImageOrientationPatient = ds_text(list(row_dir) + list(col_dir))
        ds.PixelSpacing = ds_text([spacing[1], spacing[0]])  # between rows, then between columns
        ds.SliceThickness = f"{spacing[2]:.10g}"
        ds.Rows, ds.Columns = voxels.shape[1], voxels.shape[2]
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleSlope, ds.RescaleIntercept = ("0.5", "-500") if a.rescale else ("1", "0")
        ds.PixelData = stored[k].tobytes()
        if a.rle:
            ds.compress(RLELossless)
        ds.save_as(os.path.join(a.out, f"IM{names[n]:04d}"), write_like_original=False)


if __name__ == "__main__":
    main()
