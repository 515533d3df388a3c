"""The program as it is stored (reader) and as it goes over the wire (wire.py)."""
