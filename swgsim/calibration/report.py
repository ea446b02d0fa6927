"""placeholder"""
def summarize(result): raise NotImplementedError
def render_report(result, summary, figures): raise NotImplementedError
