"""``python -m sosdyn.cli``: the ``sosdyn`` command."""
from . import main

main()
