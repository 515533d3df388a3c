"""plotbridge: run a DIY pen plotter as a LAN appliance."""

__version__ = "0.1.0"
