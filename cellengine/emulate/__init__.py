"""An emulated Universal Robots controller for testing the UR driver with the real client.

`cellengine emulate ur --host 127.0.0.2 ...` runs one emulated controller per loopback
address in its own process: the dashboard server (29999), the script port (30003) and RTDE
(30004), a simulated arm and the register handshake of ur-rtde's control script. One
thread drives everything on a 2 ms tick, so a run is repeatable.
"""
