"""MuJoCo in the testbed: the plant (:mod:`.plant`), its model, engine and statics, and the reference statics."""
