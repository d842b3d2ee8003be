"""python -m roughness.cli"""
import sys

from . import main

sys.exit(main())
