//! host-sim: the firmware's motion core on the host, in virtual time.
