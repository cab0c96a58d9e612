import pytest


@pytest.fixture(scope="session")
def house_space():
    from psgsl_pgm.search import FreeSpace
    from psgsl_pgm.sim import Camera, default_house

    house = default_house(0)
    return house, FreeSpace(house, Camera())
