"""``python -m problems NAME [args]`` runs ``problems.<NAME>.main(args)`` (NAME: fig1, lasa-all, ...)."""
import importlib
import sys


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv:
        print("usage: python -m problems NAME [args]   (e.g. run, fig1, fig2, fig3, fig4, lasa-all, "
              "demo3d, report, bench, bench-sos)", file=sys.stderr)
        return 2
    name = argv[0].replace("-", "_")
    module = importlib.import_module(f"problems.{name}")
    return module.main(argv[1:]) or 0


if __name__ == "__main__":
    sys.exit(main())
