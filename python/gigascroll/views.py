"""views"""

__all__: list[str] = []
