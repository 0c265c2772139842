#!/usr/bin/env python3
"""Print the FMU's variables as Markdown tables (from modelDescription.xml), for docs/interface.md."""
import sys

from fmpy import read_model_description

ABOVE_ZERO = 2.2250738585072014e-308   # how modelDescription.xml writes a bound "> 0"
BELOW_ONE = 0.9999999999999999         # and "< 1"


def allowed(v) -> str:
    """The values a parameter may take, as its bounds or Enumeration items say."""
    if v.type == "Enumeration":
        return ", ".join(f"{item.value} {item.name}" for item in v.declaredType.items)
    low = None if v.min is None else float(v.min)
    high = None if v.max is None else float(v.max)
    parts = []
    if low is not None:
        parts.append("> 0" if low == ABOVE_ZERO else f">= {v.min}")
    if high is not None:
        parts.append("< 1" if high == BELOW_ONE else f"<= {v.max}")
    return ", ".join(parts)


def main(path: str) -> None:
    md = read_model_description(path)
    groups = {"input": "Inputs", "output": "Outputs", "parameter": "Parameters"}
    for causality, title in groups.items():
        parameters = causality == "parameter"
        print(f"\n#### {title}\n")
        print("| name | unit | start | allowed | description |\n|---|---|---|---|---|" if parameters
              else "| name | unit | start | description |\n|---|---|---|---|")
        for v in md.modelVariables:
            if v.causality != causality:
                continue
            start = "" if v.start is None else v.start
            kind = f"{v.type} {v.declaredType.name}" if v.type == "Enumeration" else v.type
            unit = (v.unit or kind) + (f" (shown in {v.displayUnit})" if v.displayUnit else "")
            extra = f" {allowed(v)} |" if parameters else ""
            description = v.description.replace("|", "\\|")   # |i_R1| must not end a table cell
            print(f"| `{v.name}` | {unit} | {start} |{extra} {description} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "build/Gimbal2Axis.fmu")
