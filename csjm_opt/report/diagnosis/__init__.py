"""The diagnosis page (:mod:`.report`): its verdict, detail sections, figures and units."""
