"""Element tests of the laws at one point (``pilegroup lab``) and fits (``pilegroup fit``)."""
