"""`lbr demo`: the user's whole loop on the built-in simulator (plan → check → execute → film → track → compare)."""
