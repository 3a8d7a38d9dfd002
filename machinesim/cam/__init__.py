"""CAM: the design, stock and NC programs of test pieces and workpieces (no cutting, no
measuring): what a procedure cuts, as a CAM system would prepare it."""

from machinesim._submodules import submodule


def __getattr__(name: str):
    # machinesim.cam.<module> without its own import (`machinesim._submodules`)
    return submodule(__name__, name)
