"""The paper's studies, run by name through harness.studies (`torquebench study
paper_identification|paper_planning`)."""
