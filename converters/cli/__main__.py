import sys

from . import main

# Guarded: Dask's LocalCluster starts its workers with multiprocessing's "spawn", which imports the
# parent's main module again in each of them.
if __name__ == "__main__":
    sys.exit(main())
