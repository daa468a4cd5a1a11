"""rocklab: free-rocking tests of unreinforced masonry walls, from raw transducer records to overturning maps."""

#: The version's one source: pyproject.toml reads it (``tool.setuptools.dynamic``), ``rocklab --version`` prints it.
__version__ = "0.1.0"
