#!/usr/bin/env python3
"""Print the FMU's variables as a Markdown table (from modelDescription.xml), for the README."""
import sys

from fmpy import read_model_description


def main(path: str) -> None:
    md = read_model_description(path)
    groups = {"input": "Inputs", "output": "Outputs", "parameter": "Parameters"}
    for causality, title in groups.items():
        print(f"\n#### {title}\n\n| name | unit | start | description |\n|---|---|---|---|")
        for v in md.modelVariables:
            if v.causality != causality:
                continue
            start = "" if v.start is None else v.start
            unit = (v.unit or v.type) + (f" (shown in {v.displayUnit})" if v.displayUnit else "")
            print(f"| `{v.name}` | {unit} | {start} | {v.description} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "build/Gimbal2Axis.fmu")
