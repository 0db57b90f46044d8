"""sensing"""

__all__: list[str] = []
