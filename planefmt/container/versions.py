"""The format versions this reader knows, in a module of their own: ``pln --version`` names them without
importing the records' numpy and construct."""

#: Major versions read, each with the newest minor version this reader knows.
VERSIONS = {1: 0, 2: 0, 3: 4, 4: 2, 5: 2, 6: 0}
