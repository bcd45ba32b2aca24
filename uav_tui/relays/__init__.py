"""Output relays: what turns a processor output into an effect on the vehicle, behind one contract
(:class:`~uav_tui.relays.contract.OutputRelay`) and one registry the core loops over
(:data:`~uav_tui.relays.registry.REGISTRY`)."""
