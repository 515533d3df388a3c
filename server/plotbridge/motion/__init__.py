"""The firmware's own motion code built for the host, for plot time estimates:
library.py (loading it), estimate.py (running a program through it), timing.py (the
host-side timing around it), eta.py (time left of a running job; numpy-free, so this
package imports nothing on its own)."""
