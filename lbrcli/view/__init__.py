"""`lbr view`: a 3D replay in the browser of the files lbr writes (viser), and its self-contained offline file."""
