"""pack"""

__all__: list[str] = []
