#!/usr/bin/python3
"""docs/RESULTS.md from its template (tools/evidence/RESULTS.md.in) and the data the
evidence wrote (docs/results/*.json): every number in it is a fact of facts.py, put where
the template says {{name}}.

    results_doc.py [--data docs/results] [--write docs/RESULTS.md | --check docs/RESULTS.md]

--check exits 1 when the file is not the template rendered from the data (naming the first
line that differs) or names a chart the data directory does not have; --write writes it.
Without either it renders to standard output (and checks that every fact can be computed).
Exit 2 for a template that names an unknown fact or data that lacks a section.
"""

import argparse
import json
import pathlib
import re
import sys

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import facts  # noqa: E402

TOKEN = re.compile(r"\{\{([a-z0-9_.]+)\}\}")
CHART = re.compile(r"\]\((results/[^)]+)\)")


class TemplateError(ValueError):
    pass


def load(data_dir):
    data = {}
    for path in sorted(data_dir.glob("*.json")):
        with open(path, encoding="utf-8") as f:
            block = json.load(f)
        if isinstance(block, dict) and "section" in block:
            data[block["section"]] = block
    return data


def render(template, data):
    def fact(match):
        name = match.group(1)
        if name not in facts.FACTS:
            raise TemplateError(f"unknown fact {{{{{name}}}}} (known: {', '.join(facts.FACTS)})")
        try:
            return facts.FACTS[name](data)
        except KeyError as error:
            raise TemplateError(f"fact {name}: the data has no {error}") from error
    return TOKEN.sub(fact, template)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    root = HERE.parent.parent
    parser.add_argument("--data", type=pathlib.Path, default=root / "docs/results")
    parser.add_argument("--template", type=pathlib.Path, default=HERE / "RESULTS.md.in")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--write", type=pathlib.Path)
    mode.add_argument("--check", type=pathlib.Path)
    args = parser.parse_args()
    try:
        text = render(args.template.read_text(encoding="utf-8"), load(args.data))
    except (TemplateError, OSError) as error:
        print(f"results_doc.py: {error}", file=sys.stderr)
        return 2
    missing = [chart for chart in CHART.findall(text)
               if not (args.data / chart.split("/", 1)[1]).is_file()]
    if missing:
        print(f"results_doc.py: charts not in {args.data}: {', '.join(missing)}", file=sys.stderr)
        return 1
    if args.write:
        args.write.write_text(text, encoding="utf-8")
    elif args.check:
        current = args.check.read_text(encoding="utf-8").splitlines()
        for number, (want, have) in enumerate(zip(text.splitlines(), current), start=1):
            if want != have:
                print(f"results_doc.py: {args.check}:{number} is not what the data says:\n"
                      f"  file: {have}\n  data: {want}\n"
                      "regenerate it: tools/evidence/results_doc.py --write docs/RESULTS.md",
                      file=sys.stderr)
                return 1
        if len(current) != len(text.splitlines()):
            print(f"results_doc.py: {args.check} has {len(current)} lines, the data "
                  f"{len(text.splitlines())}", file=sys.stderr)
            return 1
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
