"""photon"""

__all__: list[str] = []
