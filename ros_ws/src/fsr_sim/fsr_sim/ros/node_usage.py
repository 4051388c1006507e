"""What a node's ``--help`` prints: its parameters, the topics it publishes and reads, and its exit codes.

The topics come from :mod:`fsr_sim.contract` (what the node publishes is the contract's ``publisher``), the
exit codes from its ``EXIT_CODES``; each node declares only its parameters and the topics it subscribes.
"""

from __future__ import annotations

from dataclasses import dataclass

from fsr_sim.contract import EXIT_CODES, TOPICS, Topic


@dataclass(frozen=True)
class Parameter:
    name: str
    default: str  # as it would be written after ``:=`` ("" for a required parameter)
    meaning: str


@dataclass(frozen=True)
class NodeUsage:
    """A node's command line (its console script ``command``, also its node name and contract publisher)."""

    command: str
    summary: str
    parameters: tuple[Parameter, ...]
    subscribes: tuple[Topic, ...]
    exit_codes: tuple[int, ...]

    def text(self) -> str:
        """The ``--help`` text."""
        width = max(len(p.name) + len(p.default) + 2 for p in self.parameters)
        lines = [f"usage: {self.command} [-h] [--ros-args -p name:=value ... -r __ns:=/uav1]", "", self.summary, "",
                 "parameters (-p name:=value):"]
        for p in self.parameters:
            lines.append(f"  {(p.name + ':=' + p.default if p.default else p.name):<{width}}  {p.meaning}")
        lines += ["", "publishes (relative names move with the namespace):"]
        lines += [f"  {t.name:<18} {t.type}" for t in TOPICS if t.publisher == self.command]
        lines += ["", "subscribes:"] + [f"  {t.name:<18} {t.type}" for t in self.subscribes]
        lines += ["", "exit codes:"] + [f"  {code:<3} {EXIT_CODES[code]}" for code in self.exit_codes]
        return "\n".join(lines)


def wants_help(argv: list[str]) -> bool:
    """``-h`` or ``--help`` before ``--ros-args`` (``argv[0]`` is the program)."""
    args = argv[1:]
    own = args[:args.index("--ros-args")] if "--ros-args" in args else args
    return "-h" in own or "--help" in own
