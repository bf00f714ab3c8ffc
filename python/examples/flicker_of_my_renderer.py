"""Flicker and error of another renderer's frames (Mitsuba's, yours) against irad's reference.

    python python/examples/flicker_of_my_renderer.py FRAMES_DIR --scene SCENE
        [--reference REF_DIR | --spp 256] [--fps 24] [--camera EYE:TARGET:FOV]

FRAMES_DIR holds frame_FFFF.exr (linear) or .png (sRGB) files of SCENE, a built-in or the same
glTF file the other renderer rendered, frame f at time f / fps and seen from the scene's camera
(or --camera). irad path-traces the reference for those frames at their size (or reads
--reference) and reports relMSE, flicker F1 and the warped F1, which follows each pixel's
surface along the motion so that a moving camera is not counted as flicker.

Without FRAMES_DIR it makes a stand-in: irad's CDF sampler's frames written as EXR into a
temporary folder. IRAD_EXAMPLE_TINY=1 keeps that small (the tests use it).
"""

import argparse
import os
import tempfile

import irad

TINY = bool(os.environ.get("IRAD_EXAMPLE_TINY"))


def stand_in(folder: str, scene: str) -> None:
    """Frames 'from another renderer': written to files, as any renderer would."""
    size = (16, 16) if TINY else (128, 128)
    for f in irad.render_iter(scene, frames=range(0, 6 if TINY else 24), sampler="cdf",
                              vpls=16 if TINY else 128, size=size):
        irad.write_exr(os.path.join(folder, f"frame_{f.index:04}.exr"), f.image)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("frames_dir", nargs="?")
    p.add_argument("--scene", default="cornell-orbit")
    p.add_argument("--reference", help="a folder of reference frames (else irad traces them)")
    p.add_argument("--spp", type=int, default=4 if TINY else 256)
    p.add_argument("--fps", type=float, default=24.0)
    p.add_argument("--camera", help="EYE:TARGET:FOV the frames were rendered with")
    a = p.parse_args()

    tmp = None
    if a.frames_dir is None:
        tmp = tempfile.TemporaryDirectory()
        a.frames_dir = tmp.name
        stand_in(a.frames_dir, a.scene)
        print(f"no FRAMES_DIR: scoring irad's cdf frames written to {a.frames_dir}")

    numbers, frames = irad.read_frames(a.frames_dir)
    h, w, _ = frames[0].shape
    if a.reference:
        ref_numbers, reference = irad.read_frames(a.reference)
        by_number = dict(zip(ref_numbers, reference))
        reference = [by_number[n] for n in numbers]
    else:
        print(f"tracing irad's reference: frames {numbers[0]}..{numbers[-1] + 1} at {w}x{h}, {a.spp} spp")
        reference = [
            f.image
            for f in irad.reference(a.scene, frames=(numbers[0], numbers[-1] + 1), spp=a.spp,
                                    size=(w, h), fps=a.fps, camera=a.camera)
        ]

    m = irad.metrics.sequence(frames, reference, frames=numbers)
    warped = irad.metrics.warped(frames, reference, a.scene, fps=a.fps, frames=numbers,
                                 camera=a.camera)
    print(f"{len(frames)} frames of {a.scene} at {w}x{h}")
    print(f"  relMSE      {m['mean_rel_mse']:.5f}   FLIP {m['mean_flip']:.4f}   bias {m['mean_bias']:+.5f}")
    print(f"  flicker F1  {m['flicker_f1']:.5f}")
    print(f"  warped F1   {warped['f1']:.5f}  ({100 * warped['kept']:.1f}% of pixels followed)")
    print("  (the reference's own noise adds to both: irad compare measures that floor)")
    if tmp:
        tmp.cleanup()


if __name__ == "__main__":
    main()
