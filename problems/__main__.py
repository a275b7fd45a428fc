"""``python -m problems NAME [args]`` runs the experiment NAME (see ``problems.EXPERIMENTS``)."""
import sys

from problems import EXPERIMENTS, run_experiment
from sosdyn.errors import InputError


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv:
        print(f"usage: python -m problems NAME [args]   (NAME: {', '.join(EXPERIMENTS)})", file=sys.stderr)
        return 2
    try:
        return run_experiment(argv[0], argv[1:])
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
