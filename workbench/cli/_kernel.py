"""``workbench kernel``: the code generated for a model from the compiled templates."""

from __future__ import annotations

import argparse
from pathlib import Path

from workbench.cli._console import add_quiet

__all__ = ["register_cli"]

_PARTS = ("kernel", "steps", "implicit", "jacobian", "tangent")


def _cmd_kernel(args: argparse.Namespace) -> int:
    from workbench.models import available_models
    from workbench.run import prepare
    from workbench.scene import load_scene
    from workbench.solver import generated_source

    if Path(args.model).suffix == ".toml" or Path(args.model).is_file():
        scene = load_scene(args.model)
    elif args.model in available_models():
        scene = load_scene({"model": {"name": args.model}})
    else:
        from workbench.cli._exit_codes import UsageError

        raise UsageError(
            f"MODEL: got {args.model!r}; allowed: a scene file or one of "
            f"{', '.join(available_models())}"
        )
    hooks = prepare(scene.replace(sweep={})).problem.hooks
    path, text = generated_source(hooks, args.part)
    if args.path:
        print(path)
    else:
        print(f"# {path} (generated for {hooks} from workbench/solver/_templates)")
        print(text, end="")
    return 0


def register_cli(sub) -> None:
    """Add the ``kernel`` subcommand."""
    p = sub.add_parser(
        "kernel",
        help="print the compiled code generated for a model (its integration loop, ...)",
        description="Print the module generated for a model from the templates of "
        "workbench/solver/_templates (the cache's copy; nothing is compiled).",
    )
    p.add_argument("model", help="model name (e.g. ninebar) or scene file (TOML)")
    p.add_argument(
        "--part",
        choices=_PARTS,
        default="kernel",
        help="which generated module: the integration loop (kernel, default), its explicit "
        "steps, Radau IIA's step (implicit), the Jacobian, or the tangent system's hooks",
    )
    p.add_argument("--path", action="store_true", help="print only the file's path")
    add_quiet(p, "accepted by every command; this one prints only its results")
    p.set_defaults(func=_cmd_kernel)
