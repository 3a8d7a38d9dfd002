"""CAM: the design, stock and NC programs of test pieces and workpieces (no cutting, no
measuring): what a procedure cuts, as a CAM system would prepare it."""
