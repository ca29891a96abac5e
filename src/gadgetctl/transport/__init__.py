"""OS transports shared by the drivers (imports nothing else from gadgetctl, so a driver's
standalone protocol code may use it as Gadgeteer's drivers use VPR)."""
