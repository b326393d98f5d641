"""The design pages: the sweep's design study (:mod:`.report`) and the optimisation result (:mod:`.optimisation`)."""
