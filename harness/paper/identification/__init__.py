"""The paper's identification pieces: Table IV's benchmark systems (table4) and the
published 75-feature library of its arm (published_library)."""
