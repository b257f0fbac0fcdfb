"""Paper 001's motion-control lab: the Figs. 11–13 sets, tuning of the PIDs and the RSLQR, step timing."""
