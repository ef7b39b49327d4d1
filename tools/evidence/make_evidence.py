#!/usr/bin/python3
"""Regenerates the project's evidence (docs/RESULTS.md): every figure from the project's own
programs, each section's numbers in a JSON file beside its charts.

    tools/evidence/make_evidence.py [--build build/release] [--out docs/results] [--quick]
                                    [--only SECTION,...] [--jobs N]

--quick runs few points and short runs (CI runs it, so that the evidence cannot rot); its
numbers are not the published ones. Without --only every section runs. --redraw runs
nothing and redraws the charts from the data files already in the output directory. At the end the page
is rendered from the template and every data file in the output directory: into
docs/RESULTS.md when the output is docs/results, else into OUT/RESULTS.md (not when the
directory lacks a section's data, which it says). Exit 0 done; 1 a program failed (the
message names it); 2 bad arguments or a template the data cannot fill.
"""

import argparse
import datetime
import json
import pathlib
import shutil
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "plot"))

import admittance  # noqa: E402
import context  # noqa: E402
import effort  # noqa: E402
import firmware  # noqa: E402
import identification  # noqa: E402
import identification_charts  # noqa: E402
import maps  # noqa: E402
import maps_charts  # noqa: E402
import rate  # noqa: E402
import rate_charts  # noqa: E402
import results_doc  # noqa: E402
import scene_detail  # noqa: E402
import timing  # noqa: E402
import zwidth  # noqa: E402
import zwidth_charts  # noqa: E402

# Each section: run(ctx) -> its data (written as NAME.json), and
# draw(data, out_dir, caption) -> the chart files it wrote.
SECTIONS = {"stability-maps": (maps.run, maps_charts.draw),
            "rate": (rate.run, rate_charts.draw),
            "identification": (identification.run, identification_charts.draw),
            "zwidth": (zwidth.run, zwidth_charts.draw),
            "scene-detail": (scene_detail.run, scene_detail.draw),
            "effort": (effort.run, effort.draw),
            "admittance": (admittance.run, admittance.draw),
            "firmware": (firmware.run, firmware.draw),
            "timing": (timing.run, timing.draw)}


def caption_for(name, data):
    """The caption line's common part: the run, its device, the machine."""
    quick = " (quick mode)" if data["mode"] == "quick" else ""
    return (f"hapticd {data['hapticd']} evidence, {name}{quick}; {data.get('device', '')}; "
            f"{context.describe_machine(data['machine'])}")


def arguments():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    root = HERE.parent.parent
    parser.add_argument("--build", type=pathlib.Path, default=root / "build/release",
                        help="the build tree whose bin/ holds the programs")
    parser.add_argument("--out", type=pathlib.Path, default=root / "docs/results",
                        help="where the data files and charts go")
    parser.add_argument("--quick", action="store_true", help="few points, short runs (CI)")
    parser.add_argument("--only", default="", help="comma-separated sections: " +
                        ", ".join(SECTIONS))
    parser.add_argument("--jobs", type=int, default=2, help="programs run at once (default 2)")
    parser.add_argument("--redraw", action="store_true",
                        help="run nothing: redraw the sections' charts from the data files in "
                             "--out (after a change to a chart) and render the page")
    args = parser.parse_args()
    only = [name for name in args.only.split(",") if name]
    unknown = [name for name in only if name not in SECTIONS]
    if unknown:
        parser.error(f"--only: unknown section {', '.join(unknown)} "
                     f"(allowed: {', '.join(SECTIONS)})")
    if not 1 <= args.jobs <= 64:
        parser.error(f"--jobs {args.jobs}: allowed 1 to 64")
    return args, only or list(SECTIONS)


def main():
    args, sections = arguments()
    args.out.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(tempfile.mkdtemp(prefix="hapticd-evidence-"))
    ctx = context.Context(source_dir=HERE.parent.parent, bin_dir=args.build / "bin",
                          out_dir=args.out, work_dir=work, quick=args.quick, jobs=args.jobs)
    machine = context.machine()
    try:
        version = ctx.run([ctx.program("hapticd"), "--version"], "hapticd --version").split()[-1]
        for name in sections:
            run, draw = SECTIONS[name]
            if args.redraw:
                path = args.out / f"{name}.json"
                if path.is_file():
                    data = json.loads(path.read_text())
                    data["charts"] = draw(data, args.out, caption_for(name, data))
                    path.write_text(json.dumps(data, indent=1) + "\n")
                    print(f"make_evidence: {name}: redrew {len(data['charts'])} charts")
                continue
            started = time.monotonic()
            data = run(ctx)
            data.update({"section": name, "mode": "quick" if args.quick else "full",
                         "machine": machine, "hapticd": version,
                         "date": datetime.date.today().isoformat(),
                         "seconds": round(time.monotonic() - started, 1)})
            data["charts"] = draw(data, args.out, caption_for(name, data))
            path = args.out / f"{name}.json"
            path.write_text(json.dumps(data, indent=1) + "\n")
            print(f"make_evidence: {name}: {path} and {len(data['charts'])} charts "
                  f"({data['seconds']} s)")
    except context.EvidenceError as error:
        print(f"make_evidence: {error}", file=sys.stderr)
        return 1
    finally:
        shutil.rmtree(work, ignore_errors=True)
    published = args.out.resolve() == (HERE.parent.parent / "docs/results").resolve()
    page = HERE.parent.parent / "docs/RESULTS.md" if published else args.out / "RESULTS.md"
    data = results_doc.load(args.out)
    missing = [name for name in SECTIONS if name not in data]
    if missing:
        # --only into a directory without the other sections' data: what was asked is whole,
        # the page (which quotes every section) is not made.
        print(f"make_evidence: {page} not rendered: {args.out} has no data of "
              f"{', '.join(missing)} (run those sections there, or every section)")
        return 0 if set(missing).isdisjoint(sections) else 1
    try:
        template = (HERE / "RESULTS.md.in").read_text(encoding="utf-8")
        page.write_text(results_doc.render(template, data), encoding="utf-8")
    except results_doc.TemplateError as error:
        print(f"make_evidence: {page}: {error}", file=sys.stderr)
        return 2
    print(f"make_evidence: {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
