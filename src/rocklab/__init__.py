"""rocklab: free-rocking tests of unreinforced masonry walls, from raw transducer records to overturning maps."""

__version__ = "0.1.0"
